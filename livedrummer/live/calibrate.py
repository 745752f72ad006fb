"""Measuring the input offset: clicks on a schedule, the drummer's hits, their median lag.

``livedrummer calibrate`` plays a click track (or, with no sound, shows it) and the drummer
hits along. Every hit is matched to its nearest click; a hit further than 40 % of the click
interval from any click, or a second hit on the same click, is dropped (a flam, a stray
pad), never averaged in. The lag of a hit is its stamp minus the click's time on the shared
clock; their median is what the rig must take off every onset (the module's trigger latency
plus the drummer's habit, as rhythm games calibrate it), and half their interquartile range
says how steady the hits were. :func:`estimate` needs at least :data:`MIN_HITS` matched hits.

Limits: one offset for all pads (a module's latency can differ per trigger input); the
median cannot tell a late module from a drummer who plays behind the beat, which is why the
drummer is asked to hit *on* the click; the audio and display offsets are separate
(``calibration.toml``) and this estimate does not change them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_HITS = 4
WINDOW_FRACTION = 0.4


def click_times(start_s: float, bpm: float, count: int) -> np.ndarray:
    """``count`` clicks from ``start_s``, one per beat at ``bpm``."""
    if not 20.0 <= bpm <= 400.0 or count < 1:
        raise ValueError(f"bpm {bpm:g} must be 20..400 and count {count} >= 1")
    return start_s + np.arange(count) * (60.0 / bpm)


@dataclass(frozen=True)
class OffsetEstimate:
    """The median lag of the matched hits and how spread they were (milliseconds)."""

    median_ms: float
    spread_ms: float  # half the interquartile range
    used: int
    dropped: int
    lags_ms: tuple[float, ...]


def estimate(clicks: np.ndarray, hits: np.ndarray) -> OffsetEstimate:
    """Match ``hits`` (stamps, s) to ``clicks`` (s) and estimate the lag (see the docstring)."""
    clicks = np.asarray(clicks, np.float64)
    interval = float(np.median(np.diff(clicks))) if clicks.size > 1 else 1.0
    window = WINDOW_FRACTION * interval
    taken: set[int] = set()
    lags: list[float] = []
    dropped = 0
    for hit in np.sort(np.asarray(hits, np.float64)):
        i = int(np.argmin(np.abs(clicks - hit)))
        lag = hit - clicks[i]
        if abs(lag) > window or i in taken:
            dropped += 1
            continue
        taken.add(i)
        lags.append(lag)
    if len(lags) < MIN_HITS:
        raise ValueError(
            f"{len(lags)} hits on the clicks ({dropped} off them): need at least "
            f"{MIN_HITS}; hit once on each click"
        )
    ms = np.array(lags) * 1000.0
    q1, med, q3 = np.percentile(ms, [25, 50, 75])
    return OffsetEstimate(
        float(med), float(q3 - q1) / 2.0, len(lags), dropped, tuple(float(x) for x in ms)
    )
