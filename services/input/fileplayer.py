"""File source: a Standard MIDI File played in real time, as if a drummer were performing it.

The file is read once with :func:`~livedrummer.midi.smf.read_midi_file` (the same decoder the
live sources use), its onsets and controls are merged in time order (controls first at equal
times: a module sends CC4 before its note), and each is released when the shared clock
reaches ``start + time_s``, then stamped with the clock *at release*, exactly like an event
arriving from a kit. Events due at the same instant come out in one batch. With a
:class:`~livedrummer.timeline.clock.SteppedClock` the whole file "plays" at once, deterministically.

``channel`` chooses the drum channels as for every file command (``all`` by default, as a kit's
port is read); what the file's report says (channels left out, unknown notes) is logged once.

Limits: ``open`` (re)starts the file from the top; ``loop`` restarts it after ``loop_gap_s``.
"""

from __future__ import annotations

import logging
import threading
from pathlib import Path

import numpy as np

from livedrummer.midi.channels import ChannelChoice
from livedrummer.midi.notemap import NoteMap
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import Control, ControlKind, Onset
from livedrummer.timeline.stats import DecodeStats

from .base import Event, Problems, Source

log = logging.getLogger(__name__)


class FileSource(Source):
    simulated = True

    def __init__(
        self,
        path: Path,
        clock: Clock,
        note_map: NoteMap,
        performer: int = 0,
        loop: bool = False,
        loop_gap_s: float = 1.0,
        problems: Problems | None = None,
        channel: ChannelChoice = "all",
    ) -> None:
        super().__init__(f"file:{path}", clock, problems)
        self.path = path
        self.note_map = note_map
        self.performer = performer
        self.channel = channel
        self.loop = loop
        self.loop_gap_s = loop_gap_s
        self._times = np.zeros(0)
        self._events: list[Onset | Control] = []
        self._next = 0
        self._start = 0.0
        self._length = 0.0
        self._cancel = threading.Event()
        self._stats: DecodeStats | None = None

    def decode_stats(self) -> DecodeStats | None:
        """The file's decode counts (all of the file, from the moment it is opened)."""
        return self._stats

    def load(self) -> None:
        """Read the file (a bad file is a MidiFileError here, before anything is bound)."""
        if not self._events:
            perf = read_midi_file(self.path, self.note_map, self.performer, self.channel)
            for line in perf.report_lines(self.note_map.ignored):
                log.warning("%s: %s", self.path, line)
            self._stats = perf.stats
            events: list[tuple[float, int, Onset | Control]] = []
            for c in perf.controls:
                events.append((float(c["time_s"]), 0, _control(c)))
            for o in perf.onsets:
                events.append((float(o["time_s"]), 1, Onset.from_record(o)))
            events.sort(key=lambda e: (e[0], e[1]))
            self._times = np.array([e[0] for e in events])
            self._events = [e[2] for e in events]
            self._length = max(perf.duration_s, float(self._times[-1]) if events else 0.0)

    def open(self) -> None:
        self.load()
        self._next = 0
        self._cancel.clear()
        self._start = self.clock.now()
        self.is_open = True

    def read(self, timeout_s: float) -> list[Event]:
        if self._next >= len(self._events):
            if not self.loop or not self._events:
                self._cancel.wait(timeout_s)
                return []
            self._next = 0
            self._start += self._length + self.loop_gap_s
        due = self._start + float(self._times[self._next])
        if due > self.clock.now() + timeout_s:
            self.clock.wait_until(self.clock.now() + timeout_s, self._cancel)
            return []
        if not self.clock.wait_until(due, self._cancel):
            return []
        now = self.clock.now()
        stop = int(np.searchsorted(self._times, now - self._start, side="right"))
        stop = max(stop, self._next + 1)
        out: list[Event] = []
        for event in self._events[self._next : stop]:
            if isinstance(event, Onset):
                out.append(_restamp_onset(event, now))
            else:
                out.append(_restamp_control(event, now))
        self._next = stop
        return out

    def finished(self) -> bool:
        played = self._next >= len(self._events)
        return self.is_open and played and (not self.loop or not self._events)

    def close(self) -> None:
        self._cancel.set()
        self.is_open = False


def _control(row: np.void) -> Control:
    return Control(
        float(row["time_s"]),
        ControlKind(int(row["kind"])),
        int(row["channel"]),
        int(row["number"]),
        int(row["value"]),
        int(row["source"]),
    )


def _restamp_onset(o: Onset, t: float) -> Onset:
    return Onset(
        t, o.note, o.velocity, o.channel, o.instrument, o.zone, o.hihat, o.openness, o.source
    )


def _restamp_control(c: Control, t: float) -> Control:
    return Control(t, c.kind, c.channel, c.number, c.value, c.source)
