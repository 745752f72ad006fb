"""A part of a piece, as a person names it: ``--start 12.5 --end 40`` or ``--start bar5``.

Musicians name a passage by bars ("bars 5 to 8"), editors by seconds; both are accepted. A
position is parsed from text once (:func:`parse_position`), before any file is read, so a typo
is reported before work starts; it becomes seconds only against the piece's beat grid
(:func:`span_seconds`), because a bar's time depends on the tempo map.

Bars count from 1, as in a score. A start bar means its downbeat; an end bar means the end of
that bar (the next bar's downbeat), so ``--start bar5 --end bar8`` is the four bars 5-8. The
end of the last bar is one beat past its last beat. Seconds are taken as given; a span must be
non-empty and start inside the piece (its length plus the render's tail), and an end past that
is cut to it.

Limits: a file whose grid is the default (no time signature) counts 4/4 bars at its tempo,
which is what a DAW shows for it too.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from livedrummer.timeline.tempo import Grid

_SECONDS = re.compile(r"(\d+(?:\.\d*)?|\.\d+)\s*s?")
_BAR = re.compile(r"(?:bar|b)\s*(\d+)", re.IGNORECASE)


@dataclass(frozen=True)
class Position:
    """A point in a piece: ``value`` seconds, or the 1-based bar ``value`` when ``bar``."""

    value: float
    bar: bool = False

    def __str__(self) -> str:
        return f"bar{int(self.value)}" if self.bar else f"{self.value:g} s"


def parse_position(text: str) -> Position:
    """``"12.5"``, ``"12.5s"``, ``"bar5"`` or ``"b5"``; ValueError naming what is expected."""
    t = text.strip()
    if m := _BAR.fullmatch(t):
        bar = int(m.group(1))
        if bar < 1:
            raise ValueError(f"{text!r}: bars count from 1")
        return Position(float(bar), bar=True)
    if m := _SECONDS.fullmatch(t):
        return Position(float(m.group(1)))
    raise ValueError(f"{text!r}: expected seconds (12.5) or a bar number (bar5)")


def span_seconds(
    start: Position | None, end: Position | None, grid: Grid, length_s: float
) -> tuple[float, float]:
    """(start_s, end_s) of the span within ``0..length_s``; ValueError naming the bad end."""
    lo = 0.0 if start is None else _seconds(start, grid, ending=False)
    hi = length_s if end is None else min(_seconds(end, grid, ending=True), length_s)
    if lo >= length_s:
        raise ValueError(f"start {start} is at or past the end ({length_s:.2f} s)")
    if hi <= lo:
        raise ValueError(f"end {end} is not after start {start or '0 s'}")
    return lo, hi


def _seconds(position: Position, grid: Grid, *, ending: bool) -> float:
    if not position.bar:
        return position.value
    bar = int(position.value) - 1 + (1 if ending else 0)
    return grid.bar_start_s(bar)
