"""Reading Standard MIDI Files into a :class:`~livedrummer.timeline.performance.Performance`.

mido does the message parsing; this module adds what a user needs when a file is bad and what
the rest of the library needs when it is good:

* Before mido sees the bytes, the chunk structure is checked here so that a truncated, empty
  or foreign file is reported with the byte offset and the chunk at fault (mido's own errors
  say neither). If mido still fails, the failing track is found by parsing tracks one by one.
* Ticks become seconds once, through :class:`~livedrummer.timeline.tempo.TempoMap`, for all tracks
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
* zero tempo is an error, and grids are capped (:data:`livedrummer.timeline.tempo.MAX_BEATS`).

Many notes at one tick are a correct, bounded result: one onset per note is kept and the
rest are counted as duplicates.

Lenient where it is safe, strict where it matters. A file that other readers play is read
with a warning instead of refused, when what is wrong carries no drum data: bytes after the
declared tracks (two newlines, a few KB of junk), a header whose track count differs from the
tracks the file holds, a malformed meta event or running status after SysEx
(:mod:`livedrummer.midi.repair`, run only on tracks mido refuses). RIFF-RMID files (``.rmi``)
are unwrapped. Each warning names the byte and the problem, once, and is kept in
:attr:`Performance.warnings`; a track that truly cannot be read (a truncated chunk, an event
with out-of-range data) is still a one-line error.

Drums only. :mod:`livedrummer.midi.channels` chooses the file's drum channels from the first
pass's counts (``channel="auto"``: channel 10 when notes are on several channels). The note map
may be a tuple of candidates: the one that knows most of the drum channels' notes is chosen
(``auto``, :func:`choose_map`). Doubled notes (one note twice within 1 ms, e.g. on two tracks)
are merged into one onset at the higher velocity
(:func:`~livedrummer.midi.decode.merge_doubled_notes`).
"""

from __future__ import annotations

import io
import logging
import struct
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import mido
import numpy as np

from livedrummer.errors import MidiFileError
from livedrummer.midi.channels import DRUM_BANKS, ChannelChoice, choose_drum_channels
from livedrummer.midi.chart import apply_tom_markers, drum_track
from livedrummer.midi.decode import MessageDecoder, merge_doubled_notes
from livedrummer.midi.notemap import NoteMap
from livedrummer.midi.repair import repair_track
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, Control, Onset
from livedrummer.timeline.performance import Performance
from livedrummer.timeline.tempo import Grid, TempoMap

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
    warnings: tuple[str, ...] = ()


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
    warnings: list[str] = []
    while pos < len(data):
        problem = _chunk_problem(data, pos, len(tracks))
        if problem is not None:
            # Junk after a track is no music lost; a truncated chunk before the declared
            # tracks are all there is (a file cut short).
            if tracks and (len(tracks) >= ntracks or not problem.startswith("truncated")):
                warnings.append(
                    f"byte {pos}: {problem}: the {len(data) - pos} bytes after the "
                    f"last declared track are ignored"
                )
                break
            raise MidiFileError(f"{name}: byte {pos}: {problem}")
        kind = data[pos : pos + 4]
        (length,) = struct.unpack(">I", data[pos + 4 : pos + 8])
        if kind == b"MTrk":
            tracks.append(Chunk(kind, pos, length))
        pos += 8 + length
    if not tracks:
        raise MidiFileError(f"{name}: no MTrk track chunk (header says {ntracks})")
    if len(tracks) != ntracks:  # a common writer bug, harmless: every track found is read
        warnings.append(
            f"byte 10: header declares {ntracks} tracks, file holds {len(tracks)}: "
            f"all {len(tracks)} are read"
        )
    return SmfLayout(fmt, division, tuple(tracks), tuple(warnings))


def _chunk_problem(data: bytes, pos: int, tracks: int) -> str | None:
    """What makes ``data[pos:]`` not a chunk, or None."""
    if len(data) - pos < 8:
        return f"{len(data) - pos} stray bytes where a chunk header should start"
    kind = data[pos : pos + 4]
    (length,) = struct.unpack(">I", data[pos + 4 : pos + 8])
    if kind != b"MTrk" and (not kind.isascii() or not kind.isalpha()):
        return f"corrupt chunk id {kind!r}"
    if pos + 8 + length > len(data):
        what = f"track {tracks + 1}" if kind == b"MTrk" else f"chunk {kind!r}"
        return (
            f"truncated: {what} declares {length} bytes but the file ends "
            f"{len(data) - pos - 8} bytes after its header"
        )
    return None


def unwrap_rmid(data: bytes, name: str) -> tuple[bytes, str]:
    """The Standard MIDI File inside a RIFF-RMID file (``.rmi``), and the name errors use.

    Byte offsets in later messages count from the start of the embedded file, which the name
    says. Other bytes are returned as they are.
    """
    if data[:4] != b"RIFF" or data[8:12] != b"RMID":
        return data, name
    pos = 12
    while pos + 8 <= len(data):
        kind = data[pos : pos + 4]
        (length,) = struct.unpack("<I", data[pos + 4 : pos + 8])
        if kind == b"data":
            inner = data[pos + 8 : pos + 8 + length]
            return inner, f"{name} (RMID data at byte {pos + 8})"
        pos += 8 + length + (length & 1)
    raise MidiFileError(f"{name}: byte 12: RIFF-RMID file without a 'data' chunk")


def parse_smf(data: bytes, name: str) -> tuple[mido.MidiFile, SmfLayout]:
    """Check the layout, then parse with mido; errors name the file, track and bytes.

    The layout's warnings include those of any track repaired (see the module docstring).
    """
    layout = check_layout(data, name)
    # mido gets the track chunks only, under a header that counts them: it reads the declared
    # count as a *signed* 16-bit number (0x8000 and more read no track at all, silently) and
    # fails on chunks of other kinds, which the SMF specification says to skip.
    header = struct.pack(">IHHH", 6, layout.format, len(layout.tracks), layout.division)
    body = b"".join(data[c.offset : c.offset + 8 + c.length] for c in layout.tracks)
    try:
        return mido.MidiFile(file=io.BytesIO(b"MThd" + header + body), clip=False), layout
    except _MIDO_ERRORS:
        pass
    chunks: list[bytes] = []
    warnings = list(layout.warnings)
    for i, c in enumerate(layout.tracks, start=1):
        where = f"track {i} (bytes {c.offset}-{c.offset + 8 + c.length})"
        events, found = repair_track(data, c.offset + 8, c.offset + 8 + c.length, name, where)
        chunks.append(b"MTrk" + struct.pack(">I", len(events)) + events)
        warnings += found
    repaired = SmfLayout(layout.format, layout.division, layout.tracks, tuple(warnings))
    try:
        midi = mido.MidiFile(file=io.BytesIO(b"MThd" + header + b"".join(chunks)), clip=False)
        return midi, repaired
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


MapChoice = NoteMap | Sequence[NoteMap]


def read_midi_file(
    path: Path | str, note_map: MapChoice, source: int = 0, channel: ChannelChoice = "auto"
) -> Performance:
    """Read a Standard MIDI File into a :class:`Performance` (see the module docstring).

    ``note_map``: a map, or candidate maps to choose from (:func:`choose_map`); ``channel``:
    which channels are drums (:func:`livedrummer.midi.channels.choose_drum_channels`).
    """
    path = Path(path)
    name = str(path)
    if path.is_dir():
        raise MidiFileError(f"{name}: is a directory, not a MIDI file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MidiFileError(f"{name}: cannot read: {exc.strerror or exc}") from exc
    return read_midi_bytes(data, name, note_map, source, channel)


#: General MIDI is kept unless a map with a larger table knows more than this share of a
#: file's notes more: a GM or GS file with a few notes outside 27-87 (GS's snare roll 25, say)
#: is still read as GM, not as a drum plugin's map that names every note but files GM's
#: percussion elsewhere. Smaller tables (the modules') need no margin: a Roland file with a
#: few hi-hat edge notes (22, 26) is a Roland file.
GM_MARGIN = 0.01


def choose_map(maps: Sequence[NoteMap], notes: Counter[int]) -> tuple[NoteMap, str]:
    """The map that knows most of ``notes`` (note-on counts) and the line that says so.

    ``maps`` are in :func:`~livedrummer.midi.notemap.bundled_note_maps`' order (General MIDI,
    then the smaller tables, then by name) and the first wins a tie; the line names the maps
    tied with it and why it was preferred, or else the runner-up. ``general-midi`` is kept
    while no map with a larger table knows more than :data:`GM_MARGIN` of the notes more.
    """
    if not maps:
        raise ValueError("choose_map: no candidate maps")
    total = sum(notes.values())
    known = [sum(n for note, n in notes.items() if m.knows(note)) for m in maps]
    top = max(range(len(maps)), key=lambda i: (known[i], -i))
    gm = next((i for i, m in enumerate(maps) if m.name == "general-midi"), None)
    if (
        gm is not None
        and gm != top
        and maps[top].size > maps[gm].size
        and known[top] - known[gm] <= GM_MARGIN * total
    ):
        line = (
            f"map auto: general-midi knows {known[gm]:,} of {total:,} drum notes; "
            f"{maps[top].name} knows {known[top]:,}, within {GM_MARGIN:.0%} of it, so General "
            f"MIDI is kept (--map {maps[top].name} reads the file with that map)"
        )
        return maps[gm], line
    chosen = maps[top]
    line = f"map auto: {chosen.name} knows {known[top]:,} of {total:,} drum notes"
    tied = [m for i, m in enumerate(maps) if i != top and known[i] == known[top]]
    if tied:
        if chosen.name == "general-midi":
            why = "General MIDI goes first"
        elif all(m.size > chosen.size for m in tied):
            why = f"the smallest table, {chosen.size} notes"
        else:
            why = "the smallest table, then by name"
        names = ", ".join(m.name for m in tied)
        return chosen, f"{line}, tied with {names} ({chosen.name} preferred: {why})"
    others = sorted((k, -i) for i, k in enumerate(known) if i != top)
    if others:
        k, i = others[-1]
        line += f" (next: {maps[-i].name}, {k:,})"
    return chosen, line


def read_midi_bytes(
    data: bytes,
    name: str,
    note_map: MapChoice,
    source: int = 0,
    channel: ChannelChoice = "auto",
) -> Performance:
    """As :func:`read_midi_file`, from bytes already in memory."""
    if len(data) > MAX_FILE_BYTES:
        raise MidiFileError(
            f"{name}: {len(data)} bytes, more than {MAX_FILE_BYTES} (4 MiB): not a performance"
        )
    data, where = unwrap_rmid(data, name)
    midi, layout = parse_smf(data, where)
    count = sum(len(track) for track in midi.tracks)
    if count > MAX_MESSAGES:
        raise MidiFileError(f"{name}: {count} messages, more than {MAX_MESSAGES}")
    merged, ticks = merge_tracks(midi.tracks)
    smpte = layout.division & 0x8000
    tempos: list[tuple[int, int]] = []
    meters: list[tuple[int, int, int]] = []
    notes: Counter[tuple[int, int]] = Counter()  # (channel, note) -> note-ons
    programs: dict[int, set[int]] = {}
    drum_banks: set[int] = set()
    for tick, msg in zip(ticks.tolist(), merged, strict=True):
        kind = msg.type
        if kind == "note_on":
            if msg.velocity:
                notes[msg.channel, msg.note] += 1
        elif kind == "set_tempo" and not smpte:
            if msg.tempo <= 0:
                raise MidiFileError(f"{name}: tick {tick}: tempo {msg.tempo} (must be > 0)")
            tempos.append((tick, msg.tempo))
        elif kind == "time_signature":
            if msg.numerator <= 0 or msg.denominator <= 0:
                raise MidiFileError(f"{name}: tick {tick}: bad time signature")
            meters.append((tick, msg.numerator, msg.denominator))
        elif kind == "program_change":
            programs.setdefault(msg.channel, set()).add(msg.program)
        elif kind == "control_change" and msg.control == 0 and msg.value in DRUM_BANKS:
            drum_banks.add(msg.channel)
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

    chart = _chart_map(note_map, midi.tracks)
    notices: list[str] = []
    if chart is not None:
        chosen, channels = chart, None
        merged, seconds, line = _chart_part(midi.tracks, tempo, merged, ticks)
        notices.append(line)
    else:
        by_channel: Counter[int] = Counter()
        for (ch, _), n in notes.items():
            by_channel[ch] += n
        drums = choose_drum_channels(channel, by_channel, programs, drum_banks)
        channels = drums.channels
        notices += [drums.notice] if drums.notice else []
        if isinstance(note_map, NoteMap):
            chosen = note_map
        else:
            drum_notes: Counter[int] = Counter()
            for (ch, note), n in notes.items():
                if channels is None or ch in channels:
                    drum_notes[note] += n
            chosen, line = choose_map([m for m in note_map if not m.chart], drum_notes)
            if drum_notes:  # with no drum notes, the choice means nothing
                notices.append(line)
    decoder = MessageDecoder(chosen, source, channels, drop_doubles=False)
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
    decoded = np.array(onsets, dtype=ONSET_DTYPE)
    merged_onsets = merge_doubled_notes(decoded)
    stats = decoder.stats
    stats.duplicates_removed += decoded.size - merged_onsets.size
    stats.onsets -= decoded.size - merged_onsets.size
    inner = where[len(name) + 1 :]  # "(RMID data at byte N)" for an RMID file, else ""
    return Performance(
        source=name,
        map_name=chosen.name,
        onsets=merged_onsets,
        controls=np.array(controls, dtype=CONTROL_DTYPE),
        tempo=tempo,
        grid=grid,
        duration_s=float(seconds[-1]) if seconds.size else 0.0,
        stats=stats,
        warnings=tuple(f"{inner} {w}" if inner else w for w in layout.warnings),
        notices=tuple(notices),
        channels=None if channels is None else tuple(sorted(channels)),
    )


def _chart_map(note_map: MapChoice, tracks: list[mido.MidiTrack]) -> NoteMap | None:
    """The chart map to read the file with, if it is read as a rhythm-game chart."""
    if isinstance(note_map, NoteMap):
        return note_map if note_map.chart else None
    charts = [m for m in note_map if m.chart]
    return charts[0] if charts and drum_track(tracks) is not None else None


def _chart_part(
    tracks: list[mido.MidiTrack], tempo: TempoMap, merged: list[mido.Message], ticks: np.ndarray
) -> tuple[list[mido.Message], np.ndarray, str]:
    """A chart's drum messages (tom markers applied), their seconds and the line saying so."""
    index = drum_track(tracks)
    if index is None:  # a chart map given for a file with no drum track: read it all
        part, part_ticks, others, what = merged, ticks, 0, "all tracks read as one chart part"
    else:
        part, part_ticks = merge_tracks([tracks[index]])
        others = sum(
            1
            for i, t in enumerate(tracks)
            if i != index
            for m in t
            if m.type == "note_on" and m.velocity > 0
        )
        what = f"track {tracks[index].name.strip()!r} read"
    part, part_ticks, markers = apply_tom_markers(part, part_ticks)
    line = f"rhythm-game chart: {what}, Expert gems played, {markers:,} tom markers applied"
    if others:
        line += f"; {others:,} notes on its other tracks ignored"
    return part, tempo.seconds(part_ticks), line
