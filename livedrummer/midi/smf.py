"""Reading Standard MIDI Files into a :class:`~livedrummer.timeline.performance.Performance`.

mido does the message parsing; this module adds what a user needs when a file is bad and what
the rest of the library needs when it is good:

* Before mido sees the bytes, the chunk structure is checked here so that a truncated, empty
  or foreign file is reported with the byte offset and the chunk at fault (mido's own errors
  say neither). If mido still fails, the failing track is found by parsing tracks one by one.
* Ticks become seconds once, through :class:`~livedrummer.midi.tempo.TempoMap`, for all tracks
  merged in time order; every channel message then goes through the same
  :class:`~livedrummer.midi.decode.MessageDecoder` the live input daemon uses.

Bounded work on absurd input. mido builds one Python object per message (about 0.5 KB and
a few microseconds each), so the bounds are checked as early as they can be:

* the file size, before mido sees it (:data:`MAX_FILE_BYTES`, 4 MiB: 27 times the largest
  Groove MIDI Dataset file, over two hours of playing at its density). Every event takes at
  least two bytes, so mido never holds more than ~2.1 M messages; the worst file under the
  limit, 1.4 M distinct note-ons, reads in ~18 s and ~0.75 GB on a 2-core machine;
* the message count, before tracks are merged and decoded (:data:`MAX_MESSAGES`);
* the length in seconds (:data:`MAX_DURATION_S`, 24 h): a delta time of 0x0FFFFFFF ticks,
  the largest a file can hold, is 78 hours at 480 ticks per beat and 120 bpm. Such a file is
  refused, naming the track and the tick, instead of yielding a day of silence to render;
* zero tempo is an error, and grids are capped (:data:`livedrummer.midi.tempo.MAX_BEATS`).

Many notes at one tick are a correct, bounded result: the decoder keeps one onset per
(channel, note, velocity) and counts the rest as duplicates.
"""

from __future__ import annotations

import io
import logging
import struct
from dataclasses import dataclass
from pathlib import Path

import mido
import numpy as np

from livedrummer.errors import MidiFileError
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.notemap import NoteMap
from livedrummer.midi.tempo import Grid, TempoMap
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, Control, Onset
from livedrummer.timeline.performance import Performance

log = logging.getLogger(__name__)

MAX_FILE_BYTES = 4 * 1024 * 1024
MAX_MESSAGES = 2_000_000
MAX_DURATION_S = 24 * 3600.0
# mido raises a wide, undocumented set of exception types on bad bytes (ValueError, EOFError,
# KeySignatureError, IndexError, ...). Around the parse call only, any Exception is bad input.
_MIDO_ERRORS = (Exception,)


@dataclass(frozen=True, slots=True)
class Chunk:
    kind: bytes
    offset: int  # byte offset of the chunk header
    length: int


@dataclass(frozen=True, slots=True)
class SmfLayout:
    """The validated chunk layout of a Standard MIDI File."""

    format: int
    division: int  # raw 16-bit division word
    tracks: tuple[Chunk, ...]


def check_layout(data: bytes, name: str) -> SmfLayout:
    """Validate the header and chunk structure; raise :class:`MidiFileError` with a byte offset."""
    if not data:
        raise MidiFileError(f"{name}: empty file")
    if data[:4] != b"MThd":
        raise MidiFileError(
            f"{name}: byte 0: not a Standard MIDI File (starts with {data[:4]!r}, expected b'MThd')"
        )
    if len(data) < 14:
        raise MidiFileError(f"{name}: byte {len(data)}: file ends inside the 14-byte header")
    (hlen,) = struct.unpack(">I", data[4:8])
    if hlen < 6:
        raise MidiFileError(f"{name}: byte 4: header length {hlen}, expected at least 6")
    fmt, ntracks, division = struct.unpack(">HHH", data[8:14])
    if fmt > 2:
        raise MidiFileError(f"{name}: byte 8: unknown SMF format {fmt}")
    if division == 0:
        raise MidiFileError(f"{name}: byte 12: division (ticks per beat) is 0")
    pos = 8 + hlen
    tracks: list[Chunk] = []
    while pos < len(data):
        if len(data) - pos < 8:
            raise MidiFileError(
                f"{name}: byte {pos}: {len(data) - pos} stray bytes where a chunk header "
                "should start"
            )
        kind = data[pos : pos + 4]
        (length,) = struct.unpack(">I", data[pos + 4 : pos + 8])
        if pos + 8 + length > len(data):
            what = f"track {len(tracks) + 1}" if kind == b"MTrk" else f"chunk {kind!r}"
            raise MidiFileError(
                f"{name}: byte {pos}: truncated: {what} declares {length} bytes but the file "
                f"ends {len(data) - pos - 8} bytes after its header"
            )
        if kind == b"MTrk":
            tracks.append(Chunk(kind, pos, length))
        elif not kind.isascii() or not kind.isalpha():
            raise MidiFileError(f"{name}: byte {pos}: corrupt chunk id {kind!r}")
        pos += 8 + length
    if not tracks:
        raise MidiFileError(f"{name}: no MTrk track chunk (header says {ntracks})")
    if len(tracks) != ntracks:  # common writer bug; harmless, but worth a line in the log
        log.warning("%s: header declares %d tracks, file holds %d", name, ntracks, len(tracks))
    return SmfLayout(fmt, division, tuple(tracks))


def parse_smf(data: bytes, name: str) -> tuple[mido.MidiFile, SmfLayout]:
    """Check the layout, then parse with mido; errors name the file, track and bytes."""
    layout = check_layout(data, name)
    # mido gets the track chunks only, under a header that counts them: it reads the declared
    # count as a *signed* 16-bit number (0x8000 and more read no track at all, silently) and
    # fails on chunks of other kinds, which the SMF specification says to skip.
    header = struct.pack(">IHHH", 6, layout.format, len(layout.tracks), layout.division)
    body = b"".join(data[c.offset : c.offset + 8 + c.length] for c in layout.tracks)
    try:
        return mido.MidiFile(file=io.BytesIO(b"MThd" + header + body), clip=False), layout
    except _MIDO_ERRORS as exc:
        # Some mido errors carry no text (an EOFError when an event runs past its track).
        what = str(exc) or (
            "an event runs past the end of its track"
            if isinstance(exc, EOFError)
            else type(exc).__name__
        )
        raise MidiFileError(f"{name}: {_locate_mido_error(data, layout)}: {what}") from exc


def _locate_mido_error(data: bytes, layout: SmfLayout) -> str:
    header = b"MThd" + struct.pack(">IHHH", 6, 0, 1, layout.division & 0x7FFF or 96)
    for i, chunk in enumerate(layout.tracks, start=1):
        body = data[chunk.offset : chunk.offset + 8 + chunk.length]
        try:
            mido.MidiFile(file=io.BytesIO(header + body), clip=False)
        except _MIDO_ERRORS:
            end = chunk.offset + 8 + chunk.length
            return f"track {i} (bytes {chunk.offset}-{end})"
    return "bad MIDI data"


def merge_tracks(tracks: list[list[mido.Message]]) -> tuple[list[mido.Message], np.ndarray]:
    """All tracks' messages in time order with their absolute ticks (ties keep track order).

    The same order as ``mido.merge_tracks``, without copying every message twice (which was
    60 % of the ingest time on the Groove corpus).
    """
    messages: list[mido.Message] = []
    tick_parts: list[np.ndarray] = []
    for track in tracks:
        messages.extend(track)
        deltas = np.fromiter((m.time for m in track), np.int64, len(track))
        tick_parts.append(np.cumsum(deltas))
    if not messages:
        return [], np.zeros(0, np.int64)
    ticks = np.concatenate(tick_parts)
    order = np.argsort(ticks, kind="stable")
    return [messages[i] for i in order.tolist()], ticks[order]


def _too_long(tracks: list[mido.MidiTrack], tempo: TempoMap) -> str:
    """Where a file runs past :data:`MAX_DURATION_S`: the first such event's track and tick."""
    limit = f"more than {MAX_DURATION_S / 3600:g} h: a corrupt delta time?"
    for i, track in enumerate(tracks, start=1):
        ticks = np.cumsum(np.fromiter((m.time for m in track), np.int64, len(track)))
        late = np.flatnonzero(tempo.seconds(ticks) > MAX_DURATION_S)
        if late.size:
            tick = int(ticks[late[0]])
            hours = float(tempo.seconds(ticks[late[:1]])[0]) / 3600
            return f"track {i}: tick {tick}: an event {hours:.1f} h into the file, {limit}"
    return f"the file lasts {limit}"  # not reached: some track holds the last event


def read_midi_file(path: Path | str, note_map: NoteMap, source: int = 0) -> Performance:
    """Read a Standard MIDI File into a :class:`Performance` (see the module docstring)."""
    path = Path(path)
    name = str(path)
    if path.is_dir():
        raise MidiFileError(f"{name}: is a directory, not a MIDI file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MidiFileError(f"{name}: cannot read: {exc.strerror or exc}") from exc
    return read_midi_bytes(data, name, note_map, source)


def read_midi_bytes(data: bytes, name: str, note_map: NoteMap, source: int = 0) -> Performance:
    """As :func:`read_midi_file`, from bytes already in memory."""
    if len(data) > MAX_FILE_BYTES:
        raise MidiFileError(
            f"{name}: {len(data)} bytes, more than {MAX_FILE_BYTES} (4 MiB): not a performance"
        )
    midi, layout = parse_smf(data, name)
    count = sum(len(track) for track in midi.tracks)
    if count > MAX_MESSAGES:
        raise MidiFileError(f"{name}: {count} messages, more than {MAX_MESSAGES}")
    merged, ticks = merge_tracks(midi.tracks)
    smpte = layout.division & 0x8000
    tempos: list[tuple[int, int]] = []
    meters: list[tuple[int, int, int]] = []
    for tick, msg in zip(ticks.tolist(), merged, strict=True):
        if msg.type == "set_tempo" and not smpte:
            if msg.tempo <= 0:
                raise MidiFileError(f"{name}: tick {tick}: tempo {msg.tempo} (must be > 0)")
            tempos.append((tick, msg.tempo))
        elif msg.type == "time_signature":
            if msg.numerator <= 0 or msg.denominator <= 0:
                raise MidiFileError(f"{name}: tick {tick}: bad time signature")
            meters.append((tick, msg.numerator, msg.denominator))
    if smpte:
        fps = -((layout.division >> 8) - 256)
        tempo = TempoMap.smpte(29.97 if fps == 29 else float(fps), layout.division & 0xFF or 1)
    else:
        tempo = TempoMap.build(layout.division, tempos)
    seconds = tempo.seconds(ticks)
    if seconds.size and seconds[-1] > MAX_DURATION_S:
        raise MidiFileError(f"{name}: {_too_long(midi.tracks, tempo)}")
    end_tick = int(ticks[-1]) if ticks.size else 0
    try:
        grid = Grid.build(tempo, meters, end_tick)
    except ValueError as exc:
        raise MidiFileError(f"{name}: {exc}") from exc

    decoder = MessageDecoder(note_map, source)
    onsets: list[tuple[object, ...]] = []
    controls: list[tuple[object, ...]] = []
    for time_s, msg in zip(seconds.tolist(), merged, strict=True):
        if msg.is_meta or msg.type == "sysex":
            continue
        event = decoder.feed(time_s, msg)
        if isinstance(event, Onset):
            onsets.append(event.to_record())
        elif isinstance(event, Control):
            controls.append(event.to_record())
    return Performance(
        source=name,
        map_name=note_map.name,
        onsets=np.array(onsets, dtype=ONSET_DTYPE),
        controls=np.array(controls, dtype=CONTROL_DTYPE),
        tempo=tempo,
        grid=grid,
        duration_s=float(seconds[-1]) if seconds.size else 0.0,
        stats=decoder.stats,
    )
