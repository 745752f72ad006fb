"""What a practice pass asks for: the reference's notes and clicks on the player's clock.

A *pass* is one run through the *segment* (the whole reference, or bars A to B of it with
``--bars A:B``) at a tempo *scale* (``--tempo 0.8`` plays it at 80 %; ``--bpm B`` is the scale
that makes the segment's first tempo B). Inside a pass, times are seconds since the pass
started, on the player's clock: a reference note at ``t`` is expected at ``(t - start) /
scale``. The live rig (``livedrummer practice REF``) and ``practice score --bars --tempo``
both build a pass with :func:`pass_notes`, so a take written by the rig and scored later is
judged against the very same expected times. Offsets are therefore in real milliseconds as the
player felt them, at the tempo practised.

Clicks come from the reference's own beat grid (its meter and tempo changes), accented on each
bar's first beat; the count-in repeats the segment's first bar's beats. *Quiet count* mutes the
click for OFF bars after every ON bars of a pass (the count-in always sounds). *Auto up/down*
(:class:`Ramp`) changes the bpm by a step after each pass and stops at a target or when a
pass's accuracy falls below a threshold.

A note up to 40 ms before a barline belongs to the bar after it (:data:`EARLY_S`): a human
reference's downbeat is often played a little early, and it belongs to its bar, not to the end
of the bar before (so it may lie a few ms before the pass starts). Which pass a hit belongs to:
pass 1 owns hits from its first note minus the window; a pass gives way to the next halfway
between its last note and the next pass's first; the last pass owns hits up to its end (or last
note) plus the window. A hit in the count-in before that belongs to no pass.

Limits: a meter change inside the loop is followed; a tempo ramp inside the reference is kept
(scaled), not flattened.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.timeline.tempo import Grid


@dataclass(frozen=True)
class Segment:
    """The part of the reference practised: reference seconds [start_s, end_s), bars (1-based,
    inclusive) first_bar..last_bar."""

    start_s: float
    end_s: float
    first_bar: int
    last_bar: int
    to_end: bool = False  # the segment runs to the reference's end (nothing after it)


def parse_loop(spec: str) -> tuple[int, int]:
    """``3:6`` → (3, 6); ValueError with the reason."""
    parts = spec.split(":")
    if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
        raise ValueError(f"{spec!r}: expected BAR:BAR, e.g. 3:6")
    a, b = int(parts[0]), int(parts[1])
    if a < 1 or b < a:
        raise ValueError(f"{spec!r}: bars count from 1 and the second is not before the first")
    return a, b


def segment(grid: Grid, duration_s: float, loop: tuple[int, int] | None) -> Segment:
    """The whole reference (time 0 to its end), or bars ``loop`` of its grid."""
    bars = int(grid.bar[-1]) + 1 if grid.bar.size else 0
    if loop is None:
        return Segment(0.0, float(duration_s), 1, max(1, bars), to_end=True)
    a, b = loop
    if b > bars:
        raise ValueError(f"{a}:{b}: the reference has {bars} bars")
    first = np.flatnonzero(grid.bar == a - 1)
    after = np.flatnonzero(grid.bar == b)
    start = float(grid.beat_s[first[0]])
    if after.size:
        end = float(grid.beat_s[after[0]])
    else:  # the last bar: one beat past its last beat
        last = np.flatnonzero(grid.bar == b - 1)
        step = float(np.median(np.diff(grid.beat_s))) if grid.beat_s.size > 1 else 0.5
        end = float(grid.beat_s[last[-1]]) + step
    return Segment(start, end, a, b, to_end=b == bars)


def first_bpm(grid: Grid, seg: Segment) -> float:
    """The reference's tempo (beats per minute of its grid) at the segment's start."""
    beats = grid.beat_s
    if beats.size < 2:
        return 120.0
    i = int(np.clip(np.searchsorted(beats, seg.start_s, side="right") - 1, 0, beats.size - 2))
    return 60.0 / float(beats[i + 1] - beats[i])


#: A note played up to this long before a barline belongs to the bar after it (a human
#: reference's downbeat is often a little early).
EARLY_S = 0.04


def pass_index(onsets: np.ndarray, seg: Segment) -> np.ndarray:
    """Indices of the reference's onsets inside ``seg``: from :data:`EARLY_S` before its
    start to :data:`EARLY_S` before its end (to the reference's end when it runs there)."""
    t = onsets["time_s"]
    lo = seg.start_s - EARLY_S if seg.start_s > 0 else -np.inf
    hi = np.inf if seg.to_end else seg.end_s - EARLY_S
    out: np.ndarray = np.flatnonzero((t >= lo) & (t < hi))
    return out


def pass_notes(onsets: np.ndarray, seg: Segment, scale: float) -> np.ndarray:
    """The reference's onsets inside ``seg``, their times on the pass clock (see above)."""
    if not scale > 0:
        raise ValueError(f"tempo scale {scale}: must be > 0")
    out: np.ndarray = onsets[pass_index(onsets, seg)].copy()
    out["time_s"] = (out["time_s"] - seg.start_s) / scale
    return out


def pass_length_s(seg: Segment, scale: float) -> float:
    return (seg.end_s - seg.start_s) / scale


def pass_clicks(
    grid: Grid, seg: Segment, scale: float, quiet: tuple[int, int] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(click times on the pass clock, accented) for the beats of ``seg``; ``quiet`` = (ON,
    OFF) bars mutes the click in the OFF bars of each cycle."""
    pick = (grid.beat_s >= seg.start_s - 1e-9) & (grid.beat_s < seg.end_s - 1e-9)
    times = (grid.beat_s[pick] - seg.start_s) / scale
    accent = grid.beat_in_bar[pick] == 0
    if quiet is not None:
        on, off = quiet
        bar = grid.bar[pick] - (seg.first_bar - 1)
        keep = bar % (on + off) < on
        times, accent = times[keep], accent[keep]
    return times.astype(np.float64), accent.astype(bool)


def count_in(grid: Grid, seg: Segment, scale: float, bars: int) -> tuple[np.ndarray, np.ndarray]:
    """(click times before the pass, negative, on the pass clock; accented): ``bars`` bars of
    the segment's first bar."""
    if bars <= 0:
        return np.zeros(0), np.zeros(0, dtype=bool)
    first = seg.first_bar - 1
    pick = grid.bar == first
    beats = (grid.beat_s[pick] - seg.start_s) / scale
    if beats.size == 0:
        beats = np.arange(4) * 0.5 / scale
    length = pass_length_bar(beats, grid, seg, scale)
    times = np.concatenate([beats - (bars - k) * length for k in range(bars)])
    accent = (
        np.concatenate([grid.beat_in_bar[pick] == 0] * bars)
        if pick.any()
        else (np.tile(np.arange(4) == 0, bars))
    )
    return times, accent


def pass_length_bar(beats: np.ndarray, grid: Grid, seg: Segment, scale: float) -> float:
    """The length of the segment's first bar on the pass clock."""
    after = np.flatnonzero(grid.bar == seg.first_bar)
    if after.size:
        return float(grid.beat_s[after[0]] - seg.start_s) / scale
    step = float(beats[1] - beats[0]) if beats.size > 1 else 0.5 / scale
    return step * max(1, beats.size)


def pass_bounds(
    starts_s: list[float],
    length_s: list[float],
    first_s: float,
    last_s: float,
    scales: list[float],
    window_s: float,
) -> list[tuple[float, float]]:
    """[from, to) on the shared clock of the hits each pass owns (see the module docstring).

    ``first_s``/``last_s``: the segment's first and last note on the pass clock at scale 1
    (each pass's own ``scales`` stretch them)."""
    out: list[tuple[float, float]] = []
    for p, start in enumerate(starts_s):
        lo = start + first_s / scales[p] - window_s if p == 0 else out[-1][1]
        if p == len(starts_s) - 1:
            hi = max(start + length_s[p], start + last_s / scales[p]) + window_s
        else:  # halfway between this pass's last note and the next pass's first
            nxt = starts_s[p + 1] + first_s / scales[p + 1]
            hi = (start + last_s / scales[p] + nxt) / 2
        out.append((lo, hi))
    return out


@dataclass(frozen=True)
class Ramp:
    """Auto up/down: ``step_bpm`` after each pass (negative: down), stopping after the pass at
    ``target_bpm`` (within 0.01 bpm; None: no target) or once a pass's accuracy is below
    ``min_accuracy_pct``."""

    step_bpm: float
    target_bpm: float | None = None
    min_accuracy_pct: float | None = None

    def next_bpm(self, bpm: float, accuracy_pct: float) -> float | None:
        """The next pass's bpm, or None when the drill stops here."""
        if self.min_accuracy_pct is not None and accuracy_pct < self.min_accuracy_pct:
            return None
        if self.target_bpm is not None:
            if (self.step_bpm >= 0 and bpm >= self.target_bpm - 0.01) or (
                self.step_bpm < 0 and bpm <= self.target_bpm + 0.01
            ):
                return None
            nxt = bpm + self.step_bpm
            return min(nxt, self.target_bpm) if self.step_bpm >= 0 else max(nxt, self.target_bpm)
        return bpm + self.step_bpm
