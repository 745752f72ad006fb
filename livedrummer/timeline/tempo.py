"""Tempo map and beat grid: ticks become seconds once, at the edge, and never again.

A Standard MIDI File counts time in ticks whose length in seconds changes at every tempo
event. :class:`TempoMap` holds the piecewise-linear tick → second function (vectorized, exact
per segment, no accumulated rounding). :class:`Grid` is the musical skeleton in seconds that
head bob, bar-structured motion and practice features need: every beat with its bar number and
position in the bar, following time-signature changes. A beat is one unit of the signature's
denominator (a quarter in 4/4, an eighth in 6/8), as MIDI's own metronome counts it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_TEMPO_US = 500_000  # 120 bpm, the SMF default before any tempo event
MAX_BEATS = 1_000_000  # a grid larger than this is a corrupt file, not music


@dataclass(frozen=True)
class TempoMap:
    """Piecewise-linear tick → seconds; ``tempo_us[i]`` holds from ``ticks[i]`` on."""

    ticks_per_beat: int
    ticks: np.ndarray  # int64, ascending, first = 0
    tempo_us: np.ndarray  # float64 microseconds per quarter note
    seconds_at: np.ndarray  # float64, seconds at each change

    @classmethod
    def build(cls, ticks_per_beat: int, changes: list[tuple[int, int]]) -> TempoMap:
        """From (tick, microseconds per quarter) changes in any order; last at a tick wins."""
        by_tick = {0: DEFAULT_TEMPO_US}
        for tick, tempo in sorted(changes, key=lambda c: c[0]):
            by_tick[tick] = tempo
        ticks = np.array(sorted(by_tick), dtype=np.int64)
        tempo_us = np.array([by_tick[t] for t in ticks], dtype=np.float64)
        seg_s = np.diff(ticks) * tempo_us[:-1] / (ticks_per_beat * 1e6)
        seconds_at = np.concatenate([[0.0], np.cumsum(seg_s)])
        return cls(ticks_per_beat, ticks, tempo_us, seconds_at)

    @classmethod
    def smpte(cls, frames_per_second: float, ticks_per_frame: int) -> TempoMap:
        """SMPTE division: a tick is a fixed fraction of a second; tempo events do not apply.

        Expressed as one "beat" of one second so the rest of the code needs no special case.
        """
        tpb = max(1, round(frames_per_second * ticks_per_frame))
        tempo_us = 1e6 * tpb / (frames_per_second * ticks_per_frame)
        return cls(tpb, np.zeros(1, np.int64), np.array([tempo_us]), np.zeros(1))

    def seconds(self, ticks: np.ndarray) -> np.ndarray:
        """Seconds at each tick (vectorized)."""
        t = np.asarray(ticks, dtype=np.int64)
        i = np.searchsorted(self.ticks, t, side="right") - 1
        out: np.ndarray = self.seconds_at[i] + (t - self.ticks[i]) * self.tempo_us[i] / (
            self.ticks_per_beat * 1e6
        )
        return out

    def bpm_changes(self) -> list[tuple[float, float]]:
        """(time_s, quarter-note bpm) at every tempo change."""
        return [
            (float(s), 60e6 / float(u)) for s, u in zip(self.seconds_at, self.tempo_us, strict=True)
        ]


@dataclass(frozen=True)
class Grid:
    """Every beat of the piece in seconds, with its bar and its place in the bar."""

    beat_s: np.ndarray  # float64 seconds of each beat, ascending
    bar: np.ndarray  # int32 bar index (0-based) of each beat
    beat_in_bar: np.ndarray  # int16, 0 = downbeat
    meters: tuple[tuple[float, int, int], ...]  # (time_s, numerator, denominator)

    @classmethod
    def build(cls, tempo: TempoMap, meters: list[tuple[int, int, int]], end_tick: int) -> Grid:
        """Beats up to ``end_tick`` from (tick, numerator, denominator) signature changes.

        A signature change restarts the bar count at its own tick, as notation does.
        """
        changes = {0: (4, 4)}
        for tick, num, den in sorted(meters, key=lambda m: m[0]):
            changes[tick] = (num, den)
        starts = sorted(changes)
        beat_ticks: list[np.ndarray] = []
        bars: list[np.ndarray] = []
        in_bar: list[np.ndarray] = []
        bar0 = 0
        total = 0
        for k, start in enumerate(starts):
            num, den = changes[start]
            stop = starts[k + 1] if k + 1 < len(starts) else max(end_tick, start) + 1
            step = tempo.ticks_per_beat * 4 / den
            count = int(np.ceil((stop - start) / step))
            total += count
            if total > MAX_BEATS:
                raise ValueError(f"more than {MAX_BEATS} beats: a corrupt or absurd file")
            idx = np.arange(count)
            beat_ticks.append(np.round(start + idx * step).astype(np.int64))
            bars.append(bar0 + idx // num)
            in_bar.append(idx % num)
            bar0 += -(-count // num)
        ticks = np.concatenate(beat_ticks)
        return cls(
            beat_s=tempo.seconds(ticks),
            bar=np.concatenate(bars).astype(np.int32),
            beat_in_bar=np.concatenate(in_bar).astype(np.int16),
            meters=tuple((float(tempo.seconds(np.array([t]))[0]), *changes[t]) for t in starts),
        )

    def beat_position(self, time_s: np.ndarray | float) -> np.ndarray:
        """Fractional beat index at each time (linear between beats, extrapolated past ends)."""
        t = np.asarray(time_s, dtype=np.float64)
        beats = self.beat_s
        if beats.size < 2:
            return np.zeros_like(t)
        i = np.clip(np.searchsorted(beats, t, side="right") - 1, 0, beats.size - 2)
        out: np.ndarray = i + (t - beats[i]) / (beats[i + 1] - beats[i])
        return out

    @property
    def bars(self) -> int:
        """How many bars the grid spans (0 for an empty grid)."""
        return int(self.bar[-1]) + 1 if self.bar.size else 0

    def bar_start_s(self, bar: int) -> float:
        """Seconds at the downbeat of ``bar`` (0-based); ``bar == bars`` is the end of the last
        bar (one beat past its last beat). Raises ValueError outside ``0..bars``."""
        if not 0 <= bar <= self.bars:
            raise ValueError(f"bar {bar + 1} is outside the piece's {self.bars} bars")
        if bar < self.bars:
            return float(self.beat_s[np.searchsorted(self.bar, bar)])
        last = self.beat_s[-1]
        step = float(last - self.beat_s[-2]) if self.beat_s.size > 1 else 0.5
        return float(last + step)
