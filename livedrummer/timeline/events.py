"""Onsets and control events on one timeline, as dataclasses and as numpy record arrays.

Everything inside livedrummer speaks seconds (float64) on one clock. A live event travels as
one frozen :class:`Onset` or :class:`Control`; a whole performance is two record arrays with
the dtypes below, sorted by time, so algorithms can be vectorized and the same bytes can go
over a socket. Instrument, zone and hi-hat codes index the tuples in
:mod:`livedrummer.kit.vocabulary`.

``openness`` is the hi-hat opening at the moment of the stroke, 0 (closed) … 1 (open): from the
pedal controller (CC4) when the module sent one, else from the note's own articulation. It is
NaN for every other instrument.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass
from enum import IntEnum

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENT_CODE, INSTRUMENTS, ZONES, HiHat, Zone

ONSET_DTYPE = np.dtype(
    [
        ("time_s", "<f8"),
        ("note", "u1"),
        ("velocity", "u1"),
        ("channel", "u1"),
        ("instrument", "u1"),
        ("zone", "u1"),
        ("hihat", "u1"),
        ("openness", "<f4"),
        ("source", "<u2"),
    ]
)

CONTROL_DTYPE = np.dtype(
    [
        ("time_s", "<f8"),
        ("kind", "u1"),
        ("channel", "u1"),
        ("number", "u1"),  # controller number, or note number for a choke
        ("value", "u1"),
        ("source", "<u2"),
    ]
)

#: A cue's stage part (camera, blackout) sent from the synth to its displays (protocol kind
#: STAGE_CUE): ``time_s`` is the show time it takes effect at; ``camera`` 0 keeps the camera,
#: 1..8 names one (render.camera.CAMERA_NAMES, the window's keys); ``cut`` 1 cuts there, no
#: move; ``blackout`` -1 keeps it, 0 fades back to the picture, 1 fades to black; ``bar`` the
#: bar that fired it (0: none). See :mod:`livedrummer.live.cues`.
STAGE_CUE_DTYPE = np.dtype(
    [
        ("time_s", "<f8"),
        ("bar", "<u4"),
        ("camera", "u1"),
        ("cut", "u1"),
        ("blackout", "i1"),
    ]
)


class ControlKind(IntEnum):
    """What a control event carries."""

    HIHAT_PEDAL = 0  # pedal position, value = raw controller value (see NoteMap.openness)
    CHOKE = 1  # polyphonic aftertouch on a cymbal note: value > 0 grabs, 0 releases
    STRIKE_POSITION = 2  # Roland CC16-18 sent before a note: value = position


@dataclass(frozen=True, slots=True)
class Onset:
    """One stroke: when, what and how hard, as it reached us."""

    time_s: float
    note: int
    velocity: int
    channel: int
    instrument: str
    zone: Zone
    hihat: HiHat
    openness: float
    source: int = 0

    def to_record(self) -> tuple[object, ...]:
        values = list(astuple(self))
        values[4] = INSTRUMENT_CODE[self.instrument]
        values[5] = ZONES.index(self.zone)
        values[6] = HIHATS.index(self.hihat)
        return tuple(values)

    @classmethod
    def from_record(cls, row: np.void) -> Onset:
        return cls(
            time_s=float(row["time_s"]),
            note=int(row["note"]),
            velocity=int(row["velocity"]),
            channel=int(row["channel"]),
            instrument=INSTRUMENTS[int(row["instrument"])],
            zone=ZONES[int(row["zone"])],
            hihat=HIHATS[int(row["hihat"])],
            openness=float(row["openness"]),
            source=int(row["source"]),
        )


@dataclass(frozen=True, slots=True)
class Control:
    """A continuous or state-change event that is not a stroke."""

    time_s: float
    kind: ControlKind
    channel: int
    number: int
    value: int
    source: int = 0

    def to_record(self) -> tuple[object, ...]:
        return (self.time_s, int(self.kind), self.channel, self.number, self.value, self.source)


def onsets_array(onsets: list[Onset]) -> np.ndarray:
    """Pack onsets into an :data:`ONSET_DTYPE` array (kept in the given order)."""
    return np.array([o.to_record() for o in onsets], dtype=ONSET_DTYPE)


def controls_array(controls: list[Control]) -> np.ndarray:
    return np.array([c.to_record() for c in controls], dtype=CONTROL_DTYPE)
