"""The teacher's clock: which moment of the reference the teacher drummer shows, when.

The teacher is the reference animated offline (the body library with full lookahead, as
``render`` animates a file), so its motion needs only a time: the reference second to draw at
each show time. The practice plan (:mod:`livedrummer.practice.plan`) puts pass ``k`` at
``start_s`` on the shared clock, playing reference seconds ``[seg_start_s, seg_end_s)`` at a
tempo ``scale``; a pass-clock second ``t`` is reference second ``seg_start_s + t * scale``.
:class:`TeacherClock` holds the passes as the rig plans them (a ramp plans each after the one
before is judged) and maps a show time to a reference second:

* the pass that owns a show time is the first one not yet over at it (the count-in before a
  pass, and the bar between ramp passes, belong to the pass after them); after the last pass,
  the last one;
* ``ahead_s`` (the *ahead* teacher) adds real seconds before the mapping, so the teacher plays
  what is due that long from now, at the practised tempo; a *ghost* uses 0, where the player's
  sticks should be now;
* the result is clamped to the pass's segment: in the count-in the teacher waits at the
  segment's first moment, after its end it holds the last one.

Limits: the teacher jumps at a loop's seam (bar B's end back to bar A's start) and at a ramp's
tempo change, as the plan does; an ``ahead`` teacher reaches the next pass's notes only once
that pass is planned.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class PassTime:
    """One planned pass: shared-clock start, tempo scale and the reference seconds it plays."""

    start_s: float
    scale: float
    seg_start_s: float
    seg_end_s: float

    @property
    def length_s(self) -> float:
        return (self.seg_end_s - self.seg_start_s) / self.scale


@dataclass
class TeacherClock:
    """Show time → reference second (see the module docstring)."""

    ahead_s: float = 0.0
    passes: list[PassTime] = field(default_factory=list)

    def add(self, p: PassTime) -> None:
        """Plan ``p``; a pass with the start of one planned already is ignored."""
        if not p.scale > 0 or not p.seg_end_s > p.seg_start_s:
            raise ValueError(f"pass {p}: needs scale > 0 and a segment of some length")
        if any(q.start_s == p.start_s for q in self.passes):
            return  # planned already (plans are sent again for a late display)
        self.passes.append(p)
        self.passes.sort(key=lambda q: q.start_s)

    def reference_s(self, show_s: float) -> float | None:
        """The reference second the teacher shows at ``show_s``; None before any pass."""
        if not self.passes:
            return None
        t = show_s + self.ahead_s
        owner = next((p for p in self.passes if t < p.start_s + p.length_s), self.passes[-1])
        ref = owner.seg_start_s + (t - owner.start_s) * owner.scale
        return min(max(ref, owner.seg_start_s), owner.seg_end_s)


#: ``--teacher ahead`` without seconds: half a second ahead (a beat at 120 bpm).
AHEAD_S = 0.5
TEACHER_MODES = ("ghost", "ahead", "off")


def parse_teacher(spec: str) -> tuple[str, float]:
    """``ghost``, ``off``, ``ahead`` or ``ahead:SECONDS`` → (mode, seconds ahead); ValueError
    with the reason."""
    mode, _, rest = spec.partition(":")
    if mode not in TEACHER_MODES or (rest and mode != "ahead"):
        raise ValueError(f"{spec!r}: expected ghost, off, ahead or ahead:SECONDS")
    if not rest:
        return mode, AHEAD_S if mode == "ahead" else 0.0
    try:
        seconds = float(rest)
    except ValueError:
        raise ValueError(f"{spec!r}: {rest!r} is not a number of seconds") from None
    if not 0.0 <= seconds <= 10.0:
        raise ValueError(f"{spec!r}: expected 0..10 seconds ahead")
    return mode, seconds
