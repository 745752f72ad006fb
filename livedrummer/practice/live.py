"""The live readout of a practice pass: early/late per hit, running accuracy, streak.

A hit must be shown the moment it lands, before the hits after it are known, so the per-hit
line is *provisional*: the hit is paired with the nearest unclaimed expected note of its piece
within the window (greedy, in arrival order), or shown as not matching a note. The pass's
*score* is not built from these lines: when the pass is over (its end plus the window), the
rig judges all its hits at once with :func:`~livedrummer.practice.match.match_take`, the same
function ``practice score`` runs, and that summary is the one printed, stored and reported.
The two differ only where the greedy pairing is wrong (two hits fighting over one note), and the
summary says what really counts.

The meter is a text bar, 10 ms a character over ±50 ms, ``|`` on time: ``----|-*---`` is
20 ms late.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.practice.grade import Level
from livedrummer.practice.match import PIECES


@dataclass(frozen=True)
class HitLine:
    """What the readout says about one hit."""

    time_s: float  # on the pass clock
    piece: int
    offset_ms: float | None  # None: no expected note of its piece within the window
    on_time: bool
    streak: int
    accuracy_pct: float  # provisional: on-time hits / (notes due so far + unmatched hits)

    def text(self) -> str:
        name = PIECES[self.piece]
        if self.offset_ms is None:
            return (
                f"{name:<12} {'no note of it here':<29} streak {self.streak:>3}  "
                f"{self.accuracy_pct:5.1f} %"
            )
        off = self.offset_ms
        word = "on time" if self.on_time else ("late" if off > 0 else "early")
        return (
            f"{name:<12} {meter(off)} {off:+6.1f} ms {word:<7} streak {self.streak:>3}  "
            f"{self.accuracy_pct:5.1f} %"
        )


def meter(offset_ms: float, half_ms: float = 50.0, step_ms: float = 10.0) -> str:
    """A text early/late meter (see the module docstring)."""
    cells = int(half_ms / step_ms)
    pos = int(np.clip(round(offset_ms / step_ms), -cells, cells))
    bar = ["-"] * (2 * cells + 1)
    bar[cells] = "|"
    bar[cells + pos] = "*"
    return "".join(bar)


class LiveReadout:
    """Provisional per-hit feedback over one pass's expected notes (pass clock seconds)."""

    def __init__(
        self, times_s: np.ndarray, pieces: np.ndarray, window_ms: float, level: Level
    ) -> None:
        self.times_s = np.asarray(times_s, dtype=np.float64)
        self.pieces = np.asarray(pieces)
        self.window_s = window_ms / 1e3
        self.level = level
        self.reset()

    def reset(self) -> None:
        self.claimed = np.zeros(self.times_s.size, dtype=bool)
        self.streak = 0
        self.on_time = 0
        self.stray = 0

    def process(self, time_s: float, piece: int) -> HitLine:
        near = np.flatnonzero(
            (self.pieces == piece)
            & ~self.claimed
            & (np.abs(self.times_s - time_s) <= self.window_s)
        )
        offset = None
        good = False
        if near.size:
            k = int(near[np.argmin(np.abs(self.times_s[near] - time_s))])
            self.claimed[k] = True
            offset = (time_s - float(self.times_s[k])) * 1e3
            good = abs(offset) <= self.level.window_ms
        else:
            self.stray += 1
        self.on_time += good
        self.streak = self.streak + 1 if good else 0
        due = int(np.count_nonzero(self.times_s <= time_s + self.window_s))
        judged = max(1, due + self.stray)
        return HitLine(time_s, piece, offset, good, self.streak, 100.0 * self.on_time / judged)
