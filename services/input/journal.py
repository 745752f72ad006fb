"""Writing session journals, finding them again, and exporting them as Standard MIDI Files.

The record format is :mod:`livedrummer.protocol.journal`; this module does the file I/O around it.

Flush and fsync policy. The file is opened unbuffered (``os.open`` with ``O_APPEND``) and
every batch is *one* ``os.write`` of a complete record, so as soon as ``append_*`` returns the
record is in the kernel's page cache: a crash of the daemon (kill -9, segfault) loses nothing
it had journaled. Surviving a power cut needs ``fsync``, which costs milliseconds on some
disks; it must never sit between a hit and its publication, so a background thread runs it
every ``fsync_interval_s`` (default 1 s) when records were appended since the last one, and
:meth:`JournalWriter.close` runs a last one. ``fsync_interval_s = 0`` fsyncs in line after
every record instead (slow, for tests of the policy). A power cut therefore loses at most the
last interval, and at worst leaves a torn last record that the reader skips.

One file per session, ``$LIVEDRUMMER_HOME/sessions/<id>.ldj``, the id being the local start
time, performer and process id (``20261122-031500-p0-4242``): sortable, never reused.

Export: onsets become note-ons (plus a note-off ``NOTE_S`` later, or just before the same note
sounds again), hi-hat pedal and strike-position controls become control changes, chokes
polyphonic aftertouch, on one track at a fixed tempo (default 120 bpm, 1920 ticks per beat:
0.26 ms per tick). Time zero is the session's first event.
"""

from __future__ import annotations

import datetime as dt
import logging
import os
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mido
import numpy as np

from livedrummer.errors import JournalError
from livedrummer.protocol import Gap
from livedrummer.protocol.journal import (
    SUFFIX,
    Journal,
    controls_record,
    end_record,
    file_header,
    gap_record,
    meta_record,
    onsets_record,
    read_journal,
)
from livedrummer.resources import user_home
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import ControlKind

log = logging.getLogger(__name__)

NOTE_S = 0.05
DEFAULT_BPM = 120.0
DEFAULT_TPB = 1920


def sessions_dir() -> Path:
    return user_home() / "sessions"


def new_session_id(performer: int) -> str:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    return f"{stamp}-p{performer}-{os.getpid()}"


class JournalWriter:
    """Appends records to one session file (see the module docstring for the policy)."""

    def __init__(self, path: Path, fd: int, clock: Clock, fsync_interval_s: float) -> None:
        self.path = path
        self._fd = fd
        self._clock = clock
        self._fsync_interval_s = fsync_interval_s
        self._dirty = threading.Event()
        self._closing = threading.Event()
        self._syncer: threading.Thread | None = None
        self.records = 0
        self.bytes = 0
        self.syncs = 0

    def _sync_loop(self) -> None:
        """Background fsync, so a slow disk never delays a publication."""
        while not self._closing.wait(self._fsync_interval_s):
            if self._dirty.is_set():
                self._dirty.clear()
                self._fsync()

    def _fsync(self) -> None:
        try:
            os.fsync(self._fd)
            self.syncs += 1
        except OSError as exc:
            log.error("%s: fsync failed: %s", self.path, exc.strerror or exc)

    @classmethod
    def create(
        cls,
        meta: dict[str, Any],
        clock: Clock,
        directory: Path | None = None,
        session_id: str | None = None,
        fsync_interval_s: float = 1.0,
    ) -> JournalWriter:
        directory = sessions_dir() if directory is None else directory
        performer = int(meta.get("performer", 0))
        session_id = session_id or new_session_id(performer)
        path = directory / f"{session_id}{SUFFIX}"
        try:
            directory.mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND, 0o644)
        except OSError as exc:
            raise JournalError(f"{path}: cannot create journal: {exc.strerror or exc}") from exc
        writer = cls(path, fd, clock, fsync_interval_s)
        writer._write(file_header())
        writer._write(meta_record({**meta, "session": session_id, "start_s": clock.now()}))
        if fsync_interval_s > 0:
            writer._syncer = threading.Thread(
                target=writer._sync_loop, name="journal-fsync", daemon=True
            )
            writer._syncer.start()
        return writer

    @property
    def session_id(self) -> str:
        return self.path.name.removesuffix(SUFFIX)

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        try:
            while view:
                n = os.write(self._fd, view)
                view = view[n:]
        except OSError as exc:
            raise JournalError(f"{self.path}: write failed: {exc.strerror or exc}") from exc
        self.bytes += len(data)

    def _append(self, record: bytes) -> None:
        self._write(record)
        self.records += 1
        if self._fsync_interval_s > 0:
            self._dirty.set()
        else:
            self._fsync()

    def append_onsets(self, rows: np.ndarray, arrival_s: float, first_seq: int) -> None:
        self._append(onsets_record(rows, arrival_s, first_seq))

    def append_controls(self, rows: np.ndarray, arrival_s: float, first_seq: int) -> None:
        self._append(controls_record(rows, arrival_s, first_seq))

    def append_gap(self, gap: Gap, arrival_s: float, first_seq: int) -> None:
        self._append(gap_record(gap, arrival_s, first_seq))

    def close(self, info: dict[str, Any] | None = None) -> None:
        if self._fd < 0:
            return
        self._closing.set()
        if self._syncer is not None:
            self._syncer.join()
            self._syncer = None
        try:
            self._write(end_record(info or {}, self._clock.now()))
            self._fsync()
        finally:
            os.close(self._fd)
            self._fd = -1


def load_journal(path: Path) -> Journal:
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise JournalError(f"{path}: cannot read: {exc.strerror or exc}") from exc
    return read_journal(data, str(path))


def find_session(spec: str, directory: Path | None = None) -> Path:
    """A session by path, exact id, or unique id prefix."""
    path = Path(spec)
    if path.is_file():
        return path
    directory = sessions_dir() if directory is None else directory
    exact = directory / f"{spec}{SUFFIX}"
    if exact.is_file():
        return exact
    matches = sorted(directory.glob(f"{spec}*{SUFFIX}")) if directory.is_dir() else []
    if len(matches) == 1:
        return matches[0]
    if not matches:
        raise JournalError(f"{spec}: no such session in {directory}")
    names = ", ".join(m.name.removesuffix(SUFFIX) for m in matches[:5])
    raise JournalError(f"{spec}: ambiguous session id ({names} ...)")


@dataclass(frozen=True)
class SessionInfo:
    session: str
    path: Path
    onsets: int
    controls: int
    duration_s: float
    clean: bool
    discarded_bytes: int
    stop_reason: str
    meta: dict[str, Any]


def list_sessions(directory: Path | None = None) -> list[SessionInfo]:
    directory = sessions_dir() if directory is None else directory
    out = []
    for path in sorted(directory.glob(f"*{SUFFIX}")) if directory.is_dir() else []:
        try:
            j = load_journal(path)
        except JournalError as exc:
            log.warning("%s", exc)
            continue
        times = np.concatenate([j.onsets["time_s"], j.controls["time_s"]])
        out.append(
            SessionInfo(
                session=path.name.removesuffix(SUFFIX),
                path=path,
                onsets=int(j.onsets.size),
                controls=int(j.controls.size),
                duration_s=float(times.max() - times.min()) if times.size else 0.0,
                clean=j.clean,
                discarded_bytes=j.discarded_bytes,
                stop_reason=j.stop_reason,
                meta=j.meta or {},
            )
        )
    return out


def detected_beats(journal: Journal) -> np.ndarray | None:
    """The beats the online tracker (:mod:`livedrummer.live.beat`) finds in a journal's
    onsets, cleaned into an increasing grid (a beat closer than half the median interval
    to the one before is dropped); None when it finds fewer than four."""
    from livedrummer.live.beat import downbeat_weights, onset_weights, track_beats

    on = np.sort(journal.onsets, order="time_s")
    if on.size < 8:
        return None
    times = on["time_s"].astype(np.float64)
    end = float(times[-1]) + 1.0
    beats = np.sort(track_beats(times, onset_weights(on), end, downbeats=downbeat_weights(on)))
    if beats.size < 4:
        return None
    half = 0.5 * float(np.median(np.diff(beats)))
    kept = [float(beats[0])]
    for b in beats[1:]:
        if b - kept[-1] >= half:
            kept.append(float(b))
    return np.array(kept) if len(kept) >= 4 else None


def journal_to_midi(
    journal: Journal,
    bpm: float = DEFAULT_BPM,
    ticks_per_beat: int = DEFAULT_TPB,
    beats: np.ndarray | None = None,
) -> mido.MidiFile:
    """One-track SMF of a journal (see the module docstring for the mapping). With
    ``beats`` (clock times, increasing: :func:`detected_beats`), the file's tempo map puts a
    beat at each of them (a tempo event per beat; before the first and after the last, their
    neighbours' tempo), so a sequencer's bars follow the playing; else one tempo, ``bpm``."""
    if not 1.0 <= bpm <= 1000.0:
        raise JournalError(f"export tempo {bpm} bpm out of range 1..1000")
    on, ctl = journal.onsets, journal.controls
    times = np.concatenate([on["time_s"], ctl["time_s"]])
    origin = float(times.min()) if times.size else 0.0
    ticks_per_s = ticks_per_beat * bpm / 60.0
    grid: np.ndarray | None = None
    if beats is not None and beats.size >= 2:
        # the beats, extended a beat before the first sound and after the last
        first, last = float(beats[1] - beats[0]), float(beats[-1] - beats[-2])
        before = np.arange(float(beats[0]) - first, origin - first, -first)[::-1]
        end = float(times.max()) if times.size else float(beats[-1])
        after = np.arange(float(beats[-1]) + last, end + 2 * last, last)
        grid = np.concatenate([before, beats, after])

    def tick(t: float) -> int:
        if grid is not None:
            index = float(np.interp(t, grid, np.arange(grid.size, dtype=np.float64)))
            return round(index * ticks_per_beat)
        return round((t - origin) * ticks_per_s)

    # (tick, order, message): controls first at a tick (CC4 precedes its note), then
    # note-offs, then note-ons.
    events: list[tuple[int, int, int, mido.Message]] = []
    serial = 0
    for row in ctl:
        kind, ch, num, val = (
            int(row["kind"]),
            int(row["channel"]),
            int(row["number"]),
            int(row["value"]),
        )
        if kind == ControlKind.CHOKE:
            msg = mido.Message("polytouch", channel=ch, note=num, value=val)
        else:
            msg = mido.Message("control_change", channel=ch, control=num, value=val)
        events.append((tick(float(row["time_s"])), 0, serial, msg))
        serial += 1
    order = np.argsort(on["time_s"], kind="stable")
    pending_off: dict[tuple[int, int], int] = {}
    for i in order.tolist():
        row = on[i]
        ch, note, t = int(row["channel"]), int(row["note"]), tick(float(row["time_s"]))
        key = (ch, note)
        if key in pending_off:
            off = min(pending_off.pop(key), t)
            events.append((off, 1, serial, mido.Message("note_off", channel=ch, note=note)))
            serial += 1
        on_msg = mido.Message("note_on", channel=ch, note=note, velocity=int(row["velocity"]))
        events.append((t, 2, serial, on_msg))
        serial += 1
        pending_off[key] = t + max(1, round(NOTE_S * ticks_per_s))
    for (ch, note), off in pending_off.items():
        events.append((off, 1, serial, mido.Message("note_off", channel=ch, note=note)))
        serial += 1
    events.sort(key=lambda e: e[:3])
    mid = mido.MidiFile(type=0, ticks_per_beat=ticks_per_beat)
    track = mido.MidiTrack()
    if grid is None:
        track.append(mido.MetaMessage("set_tempo", tempo=round(60_000_000 / bpm), time=0))
    else:  # a tempo event on each beat: its length to the next
        for k, length in enumerate(np.diff(grid)):
            tempo = min(max(round(length * 1e6), 1), 0xFFFFFF)
            events.append((k * ticks_per_beat, -1, -1, mido.MetaMessage("set_tempo", tempo=tempo)))
        events.sort(key=lambda e: e[:3])
    now = 0
    for t, _, _, msg in events:
        track.append(msg.copy(time=t - now))
        now = t
    track.append(mido.MetaMessage("end_of_track", time=0))
    mid.tracks.append(track)
    return mid


def export_session(
    source: Path,
    out: Path,
    bpm: float = DEFAULT_BPM,
    ticks_per_beat: int = DEFAULT_TPB,
    detect: bool = False,
) -> Journal:
    """Write a journal as MIDI; ``detect``: with the detected tempo map (else ``bpm``)."""
    journal = load_journal(source)
    beats = detected_beats(journal) if detect else None
    mid = journal_to_midi(journal, bpm, ticks_per_beat, beats)
    try:
        mid.save(out)
    except OSError as exc:
        raise JournalError(f"{out}: cannot write: {exc.strerror or exc}") from exc
    return journal
