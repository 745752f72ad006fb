"""Turning MIDI channel messages into onsets and control events, one message at a time.

This is the single place where MIDI meets the drum model, used unchanged by the file reader
(offline) and by the input daemon (live): feed it ``(time_s, message)`` pairs in time order and
it returns an :class:`~livedrummer.timeline.events.Onset`, a
:class:`~livedrummer.timeline.events.Control` or ``None``. It keeps the little state MIDI requires:
the latest hi-hat pedal position per channel (modules send CC4 *before* the note) and the notes
already seen at the current instant, to drop Kragtwijk's "double events" (same time, channel, note
and velocity; they add no information). Live, that is all that can be done: an onset is
published when it comes. A file knows more, so the file reader decodes with
``drop_doubles=False`` and merges afterwards with :func:`merge_doubled_notes`: the same note
within :data:`DOUBLE_WINDOW_S` (1 ms) of its previous onset, on any channel read and at any
velocity (two tracks doubling a note), is one hit at the higher velocity.

Channels. ``channels`` (``None``: all) is the set of MIDI channels (0-based) read as drums. The
notes of other channels are counted per channel, never looked up in the map (a keyboard sharing
the port, or the bass of a full-band song, are not drums).

Nothing is dropped silently: note-ons the map does not know, notes the map lists as *ignored*
(metronome clicks and other sounds with no place on a drum kit), notes on other channels,
duplicates, and message types we do not use are all counted in
:class:`~livedrummer.timeline.stats.DecodeStats`, which callers report.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from livedrummer.kit.vocabulary import HiHat
from livedrummer.midi.notemap import NoteMap
from livedrummer.timeline.events import Control, ControlKind, Onset
from livedrummer.timeline.stats import DecodeStats

STRIKE_POSITION_CCS = frozenset({16, 17, 18})
#: Two onsets of one note this close (seconds, inclusive) are one hit.
DOUBLE_WINDOW_S = 0.001


class ChannelMessage(Protocol):
    """The part of ``mido.Message`` the decoder reads.

    mido messages only carry the attributes of their type (a control change has no ``note``);
    the decoder reads each attribute only for the types that have it.
    """

    type: str
    channel: int
    note: int
    velocity: int
    control: int
    value: int


class MessageDecoder:
    """Stateful MIDI → event decoder for one source (see the module docstring)."""

    def __init__(
        self,
        note_map: NoteMap,
        source: int = 0,
        channels: frozenset[int] | None = None,
        *,
        drop_doubles: bool = True,
    ) -> None:
        self.note_map = note_map
        self.source = source
        self.channels = channels
        self.drop_doubles = drop_doubles
        self.stats = DecodeStats()
        self._pedal: dict[int, int] = {}
        self._instant = float("nan")
        self._seen_now: set[tuple[int, int, int]] = set()

    def reset(self) -> None:
        self.stats = DecodeStats()
        self._pedal.clear()
        self._instant = float("nan")
        self._seen_now.clear()

    def feed(self, time_s: float, msg: ChannelMessage) -> Onset | Control | None:
        kind = msg.type
        channels = self.channels
        if channels is not None and msg.channel not in channels:
            if kind == "note_on" and msg.velocity > 0:
                self.stats.other_channel_notes[msg.channel] += 1
            else:
                self.stats.ignored["other channel"] += 1
            return None
        if kind == "note_on" and msg.velocity > 0:
            return self._note_on(time_s, msg)
        if kind == "control_change":
            return self._control(time_s, msg)
        if kind == "polytouch":
            return self._polytouch(time_s, msg)
        self.stats.ignored["note_off" if kind == "note_on" else kind] += 1
        return None

    def hihat_openness(self, channel: int) -> float | None:
        """Current pedal openness on ``channel``, or None before any pedal message."""
        value = self._pedal.get(channel)
        return None if value is None else self.note_map.openness(value)

    def _note_on(self, time_s: float, msg: ChannelMessage) -> Onset | None:
        note, velocity, channel = msg.note, msg.velocity, msg.channel
        stats = self.stats
        stats.note_ons[note] += 1
        if self.drop_doubles:
            if time_s != self._instant:
                self._instant = time_s
                self._seen_now.clear()
            key = (channel, note, velocity)
            if key in self._seen_now:
                stats.duplicates_removed += 1
                return None
            self._seen_now.add(key)
        spec = self.note_map.lookup(note)
        if spec is None:
            if note in self.note_map.ignored:
                stats.ignored_notes[note] += 1
            else:
                stats.unknown_notes[note] += 1
            return None
        openness = float("nan")
        if spec.hihat is not HiHat.NONE:
            pedal = self.hihat_openness(channel)
            if spec.hihat is HiHat.PEDAL:
                openness = 0.0
            else:
                openness = spec.hihat.nominal_openness if pedal is None else pedal
        stats.onsets += 1
        return Onset(
            time_s,
            note,
            velocity,
            channel,
            spec.instrument,
            spec.zone,
            spec.hihat,
            openness,
            self.source,
        )

    def _control(self, time_s: float, msg: ChannelMessage) -> Control | None:
        number, value, channel = msg.control, msg.value, msg.channel
        if number == self.note_map.hihat_cc:
            self._pedal[channel] = value
            self.stats.hihat_pedal += 1
            kind = ControlKind.HIHAT_PEDAL
        elif number in STRIKE_POSITION_CCS:
            self.stats.strike_positions += 1
            kind = ControlKind.STRIKE_POSITION
        else:
            self.stats.ignored[f"control_change {number}"] += 1
            return None
        return Control(time_s, kind, channel, number, value, self.source)

    def _polytouch(self, time_s: float, msg: ChannelMessage) -> Control | None:
        note = msg.note
        if self.note_map.lookup(note) is None:
            self.stats.ignored["polytouch on an unmapped note"] += 1
            return None
        self.stats.chokes += 1
        return Control(time_s, ControlKind.CHOKE, msg.channel, note, msg.value, self.source)


def merge_doubled_notes(onsets: np.ndarray, window_s: float = DOUBLE_WINDOW_S) -> np.ndarray:
    """Onsets (ONSET_DTYPE, sorted by time) with doubled notes merged; see the module docstring.

    A run of onsets of one note, each within ``window_s`` of the one before, is one hit: the
    first one's time, channel and openness, the run's highest velocity. The caller counts
    ``onsets.size - result.size`` as duplicates removed.
    """
    if onsets.size < 2:
        return onsets
    order = np.lexsort((onsets["time_s"], onsets["note"]))  # by note, then time (stable)
    notes, times = onsets["note"][order], onsets["time_s"][order]
    double = (notes[1:] == notes[:-1]) & (np.diff(times) <= window_s + 1e-12)
    if not double.any():
        return onsets
    first = np.flatnonzero(np.concatenate(([True], ~double)))
    velocity = onsets["velocity"].copy()
    velocity[order[first]] = np.maximum.reduceat(velocity[order], first)
    keep = np.sort(order[first])
    out = onsets[keep]
    out["velocity"] = velocity[keep]
    return out
