"""Where will each hand strike next? A per-hand inter-onset predictor for live upswings.

Why this shape. Live there is no pre-roll: with a visual delay D and a limb lookahead L the
synth may show a stroke only ``D - L`` ahead of knowing it, far less than a preparation
(about 50 ms). Most groove notes are regular per hand (hi-hat eighths, snare backbeats), so
a hand's recent inter-onset intervals predict its next onset well enough to start the
upswing in time. Each hand keeps its own history (times, piece, zone, velocity of its
committed notes); a prediction is the last note's piece and zone at ``last + next interval``,
the interval taken from the short cycle (1 to 4 intervals) that best repeats in the history
(:func:`next_interval`), with the loudest recent velocity.

Limits: no tempo model or bar pattern beyond four intervals (a fill or a syncopation is
predicted wrong, and then the body settles back and the real hit strikes fast); intervals
longer than ``max_ioi_s`` are treated as rests and restart the history.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class Guess:
    """A predicted hand note (performance time on the shared clock)."""

    time_s: float
    limb: int  # 0 right hand, 1 left hand
    piece: int
    zone: int
    velocity: int
    period_s: float


class HandPredictor:
    """Per-hand median-IOI predictor (see the module docstring)."""

    def __init__(self, history: int = 9, max_ioi_s: float = 2.5, min_ioi_s: float = 0.06) -> None:
        self.history = history
        self.max_ioi_s = max_ioi_s
        self.min_ioi_s = min_ioi_s
        self.reset()

    def reset(self) -> None:
        self._times: list[deque[float]] = [deque(maxlen=self.history + 1) for _ in range(2)]
        self._last: list[tuple[int, int, int] | None] = [None, None]
        self._velocity: list[deque[int]] = [deque(maxlen=4) for _ in range(2)]

    def observe(self, time_s: float, limb: int, piece: int, zone: int, velocity: int) -> None:
        """A committed hand note (limb 0 or 1), in time order per hand."""
        if limb not in (0, 1):
            return
        times = self._times[limb]
        if times and time_s - times[-1] > self.max_ioi_s:
            times.clear()
        if times and time_s - times[-1] < 1e-3:  # a chord on one hand: keep one
            return
        times.append(time_s)
        self._last[limb] = (piece, zone, velocity)
        self._velocity[limb].append(velocity)

    def guess(self, limb: int, after_s: float) -> Guess | None:
        """The hand's next expected note strictly after ``after_s``, or None without a rhythm."""
        times = self._times[limb]
        last = self._last[limb]
        if len(times) < 3 or last is None:
            return None
        ioi = np.diff(np.asarray(times))
        period = next_interval(ioi)
        if not self.min_ioi_s <= period <= self.max_ioi_s:
            return None
        t = times[-1] + period
        skipped = 0
        while t <= after_s:  # missed expectations: keep the rhythm, give up after two
            t += float(np.median(ioi[-4:]))
            skipped += 1
            if skipped > 2:
                return None
        # prepare for the loudest recent stroke: an accent is then seen coming, and a softer
        # hit only strikes from a little higher
        return Guess(t, limb, last[0], last[1], max(self._velocity[limb]), period)


def next_interval(ioi: np.ndarray, max_cycle: int = 4) -> float:
    """The next inter-onset interval of a hand: the pattern's cycle (1 to ``max_cycle``
    intervals, the one that best repeats over the history; shortest on ties) says which past
    interval comes again, so swung eighths (long, short) are predicted as well as straight
    ones. With three intervals or fewer, their median."""
    if ioi.size <= 3:
        return float(np.median(ioi))
    best, best_err = 1, np.inf
    for k in range(1, min(max_cycle, ioi.size - 1) + 1):
        err = float(np.mean(np.abs(ioi[k:] - ioi[:-k])))
        if err < best_err - 1e-3:
            best, best_err = k, err
    return float(ioi[-best])
