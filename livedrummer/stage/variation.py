"""Copies of one part made to differ: ChoreoGraphics' time warping and amplitude variation.

A drum line or a wall of drummers playing one part in perfect lockstep looks like one drummer
copied, which it is. The ChoreoGraphics thesis makes a chorus line look human with two
signal edits, seeded so a show is reproducible; here they act on the part's onsets (and its
controls, so a hi-hat pedal moves with its hits), and the body then plays the edited part, so
every stroke still ends on its drum:

* **Time warping**, a monotonic function that wanders around the identity. Per bar (the
  default, ``mode="bar"``), as the thesis does per measure: in each bar of length ``N``
  seconds, a random amplitude ``A`` in ``0..warp_s``, a frequency ``f`` in ``0.5..freq_max``
  cycles per bar, a half cycle of length ``N0 = N / (2f)`` placed at a random ``x0`` inside
  the bar and a random sign ``s``; then ``w(x) = x + s·A·sin(2πf(x - x0)/N)`` inside
  ``x0..x0+N0`` and ``w(x) = x`` elsewhere. Each bar's downbeat is left in place, so the
  group drifts apart and comes back together on the one, and ``w`` is monotonic because
  ``A·2πf/N < 1`` is enforced. Over the whole piece (``mode="piece"``), the thesis's second
  form ``w(x) = x + A(x)·sin(2π f(x) x / N)`` with ``A(x)`` and ``f(x)`` drawn at a knot every
  :data:`KNOT_BARS` bars and smoothly interpolated, ``N`` the mean bar; it is checked
  monotonic on the onsets and scaled down where it would not be.
* **Amplitude variation**: a gain that takes one of ``1 - R``, ``1``, ``1 + R``
  (``amplitude = R``, 0.2 in the thesis), chosen per knot and held for two knots ("repeating two
  by two"), smoothly interpolated (a cubic Hermite curve with zero slope at the knots, which
  keeps the curve within the three values as the thesis's monotone interpolation does). The
  gain scales each hit's velocity, and with it the height of the stroke (the body lifts higher
  for louder hits) and the hit's loudness.

Live, a warp must not move a hit earlier than it arrives nor later than the visual delay
allows: :func:`bounded` caps ``warp_s`` at ``delay - lookahead`` for that use.

Live there are no bar lines to warp by (the stream does not know them) and no lookahead to
move a hit earlier, so :func:`live_shift` is the live twin of the warp: a shift that is a
smooth function of the onset time alone, ``0 <= shift(t) <= warp_s``, drawn at a knot every
:data:`LIVE_KNOT_S` seconds from the seed and the knot's index (no state: any time can be asked
in any order, and two synths with one seed agree) and joined by the same zero-slope Hermite
curve as the gain; :func:`live_gain` is the amplitude variation on the same knots. The shift
never makes a hit show before it is heard, and with ``warp_s <= delay - lookahead``
(:func:`bounded`) its contact still lands within the visual delay. Its slope is at most
``1.5·warp_s / LIVE_KNOT_S`` (under 0.19), so shifted hits keep their order.

Limits: warping moves hits by at most ``warp_s`` (30 ms by default, well inside a beat), so
two hits of one part never swap order; velocities are clipped to 1..127.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MODES = ("bar", "piece")
KNOT_BARS = 2  # amplitude and piece-mode warp knots every this many bars
LIVE_KNOT_S = 2.0  # live shift and gain knots every this many seconds


@dataclass(frozen=True)
class Variation:
    """How copies differ; ``seed`` makes a copy's variation reproducible."""

    warp_s: float = 0.03
    freq_max: float = 2.0
    amplitude: float = 0.2
    mode: str = "bar"
    seed: int = 0

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"mode {self.mode!r}: expected bar or piece")
        if not 0 <= self.warp_s <= 0.25:
            raise ValueError(f"warp {self.warp_s * 1000:g} ms: expected 0..250 ms")
        if not 0.5 <= self.freq_max <= 8:
            raise ValueError(f"frequency {self.freq_max:g}: expected 0.5..8 cycles per bar")
        if not 0 <= self.amplitude < 1:
            raise ValueError(f"amplitude {self.amplitude:g}: expected 0..1")


def bounded(variation: Variation, delay_s: float, lookahead_s: float) -> Variation:
    """``variation`` with its warp capped for live use: within the visual delay's slack."""
    from dataclasses import replace

    return replace(variation, warp_s=min(variation.warp_s, max(0.0, delay_s - lookahead_s)))


def bar_edges(bar_starts: np.ndarray, end_s: float) -> np.ndarray:
    """Bar boundaries in seconds: the downbeats, then one more bar past ``end_s``."""
    starts = np.asarray(bar_starts, np.float64)
    if starts.size == 0:
        starts = np.array([0.0])
    step = float(np.diff(starts)[-1]) if starts.size > 1 else 2.0
    edges = list(starts)
    while edges[-1] <= end_s:
        edges.append(edges[-1] + step)
    return np.array(edges)


def warp_times(times: np.ndarray, edges: np.ndarray, variation: Variation) -> np.ndarray:
    """``w(times)`` (see the module docstring), for bars with boundaries ``edges``."""
    t = np.asarray(times, np.float64)
    if variation.warp_s == 0 or t.size == 0:
        return t.copy()
    rng = np.random.default_rng([variation.seed, 1])
    if variation.mode == "bar":
        return _bar_warp(t, edges, variation, rng)
    return _piece_warp(t, edges, variation, rng)


def _bar_warp(
    t: np.ndarray, edges: np.ndarray, v: Variation, rng: np.random.Generator
) -> np.ndarray:
    out = t.copy()
    for k in range(edges.size - 1):
        start, n = float(edges[k]), float(edges[k + 1] - edges[k])
        a = rng.uniform(0.0, v.warp_s)
        f = rng.uniform(0.5, v.freq_max)
        a = min(a, 0.9 * n / (2 * math.pi * f))  # w' = 1 + a·2πf/N·cos(...) > 0
        n0 = n / (2 * f)
        x0 = rng.uniform(0.0, max(n - n0, 0.0))
        sign = 1.0 if rng.uniform(-1.0, 1.0) >= 0 else -1.0
        x = t - start
        inside = (x > x0) & (x <= x0 + n0) & (x >= 0) & (x < n)
        out[inside] += sign * a * np.sin(2 * math.pi * f * (x[inside] - x0) / n)
    return out


def _smooth(knot_t: np.ndarray, knot_v: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Cubic Hermite through the knots with zero slope at each (stays between neighbours)."""
    i = np.clip(np.searchsorted(knot_t, t, side="right") - 1, 0, knot_t.size - 2)
    u = np.clip((t - knot_t[i]) / (knot_t[i + 1] - knot_t[i]), 0.0, 1.0)
    s = u * u * (3 - 2 * u)
    out: np.ndarray = knot_v[i] + (knot_v[i + 1] - knot_v[i]) * s
    return out


def _knots(edges: np.ndarray) -> np.ndarray:
    knots = edges[::KNOT_BARS]
    if knots.size < 2:
        knots = np.array([edges[0], edges[-1]])
    return knots


def _piece_warp(
    t: np.ndarray, edges: np.ndarray, v: Variation, rng: np.random.Generator
) -> np.ndarray:
    knots = _knots(edges)
    n = float(np.mean(np.diff(edges)))
    amp = _smooth(knots, rng.uniform(0.0, v.warp_s, knots.size), t)
    freq = _smooth(knots, rng.uniform(0.5, v.freq_max, knots.size), t)
    shift = amp * np.sin(2 * math.pi * freq * t / n)
    out: np.ndarray = t + shift
    order = np.argsort(t, kind="stable")
    scale = 1.0
    while scale > 1e-3 and np.any(np.diff(out[order]) < 0):  # keep the hits in their order
        scale *= 0.5
        out = t + scale * shift
    return out


def gains(times: np.ndarray, edges: np.ndarray, variation: Variation) -> np.ndarray:
    """The amplitude gain at each time (see the module docstring)."""
    t = np.asarray(times, np.float64)
    if variation.amplitude == 0 or t.size == 0:
        return np.ones_like(t)
    rng = np.random.default_rng([variation.seed, 2])
    knots = _knots(edges)
    r = variation.amplitude
    picks = rng.choice(np.array([1 - r, 1.0, 1 + r]), size=(knots.size + 1) // 2)
    values = np.repeat(picks, 2)[: knots.size]
    return _smooth(knots, values, t)


def vary_rows(
    onsets: np.ndarray, controls: np.ndarray, edges: np.ndarray, variation: Variation
) -> tuple[np.ndarray, np.ndarray]:
    """Copies of the onset and control record arrays with times warped (both by the same
    ``w``) and onset velocities scaled by the gain, clipped to 1..127."""
    on, ctl = onsets.copy(), controls.copy()
    on["time_s"] = warp_times(onsets["time_s"], edges, variation)
    ctl["time_s"] = warp_times(controls["time_s"], edges, variation)
    g = gains(onsets["time_s"], edges, variation)
    on["velocity"] = np.clip(np.rint(onsets["velocity"] * g), 1, 127).astype(on["velocity"].dtype)
    order_on, order_ctl = (
        np.argsort(on["time_s"], kind="stable"),
        np.argsort(ctl["time_s"], kind="stable"),
    )
    return on[order_on], ctl[order_ctl]


def _live_knots(
    times: np.ndarray, seed: int, stream: int, values: np.ndarray | None, high: float
) -> np.ndarray:
    """The value at each time of a curve through seeded knots every :data:`LIVE_KNOT_S`
    seconds: uniform in ``0..high``, or picked from ``values`` when given."""
    k = np.floor(times / LIVE_KNOT_S).astype(np.int64)
    out = np.empty_like(times)
    for i in np.unique(k):
        knot_v = np.empty(2)
        for j in (0, 1):
            rng = np.random.default_rng([seed, stream, int(i + j) & 0x7FFFFFFFFFFFFFFF])
            knot_v[j] = rng.choice(values) if values is not None else rng.uniform(0.0, high)
        sel = k == i
        knot_t = np.array([i * LIVE_KNOT_S, (i + 1) * LIVE_KNOT_S])
        out[sel] = _smooth(knot_t, knot_v, times[sel])
    return out


def live_shift(times: np.ndarray, variation: Variation) -> np.ndarray:
    """The live time shift at each onset time, in ``0..warp_s`` (see the module docstring)."""
    t = np.asarray(times, np.float64)
    if variation.warp_s == 0 or t.size == 0:
        return np.zeros_like(t)
    shift: np.ndarray = np.clip(
        _live_knots(t, variation.seed, 3, None, variation.warp_s), 0, variation.warp_s
    )
    return shift


def live_gain(times: np.ndarray, variation: Variation) -> np.ndarray:
    """The live amplitude gain at each onset time, in ``1 - R .. 1 + R``."""
    t = np.asarray(times, np.float64)
    if variation.amplitude == 0 or t.size == 0:
        return np.ones_like(t)
    r = variation.amplitude
    return _live_knots(t, variation.seed, 4, np.array([1 - r, 1.0, 1 + r]), 0.0)


def vary_live(onsets: np.ndarray, variation: Variation) -> np.ndarray:
    """A copy of live onset rows, each delayed by :func:`live_shift` and its velocity scaled by
    :func:`live_gain` (clipped to 1..127); rows stay in their order."""
    on = onsets.copy()
    t = onsets["time_s"].astype(np.float64)
    on["time_s"] = t + live_shift(t, variation)
    g = live_gain(t, variation)
    on["velocity"] = np.clip(np.rint(onsets["velocity"] * g), 1, 127).astype(on["velocity"].dtype)
    return on
