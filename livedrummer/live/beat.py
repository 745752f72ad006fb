"""An online beat tracker on live drum onsets: tempo and beat phase, causally.

Method (our own, after the published trackers' two stages: a tempo from the periodicity of
recent onsets, then the phase of a beat grid fitted to them; cf. BTrack's comb-filtered
autocorrelation and madmom's online tracking):

* **Evidence.** Each onset weighs its velocity times its instrument's share of the beat:
  kick and snare mark beats and backbeats (1.0), cymbals and toms less (0.6), the hi-hat's
  and ride's steady subdivisions least (0.35), so a busy hi-hat does not pull the tempo to
  eighths. Only the last ``window_s`` seconds count.
* **Tempo.** For each candidate period (log-spaced, ``min_bpm``..``max_bpm``), a comb score:
  every pair of onsets whose distance lies near 1, 2, 3 or 4 periods adds the product of
  their weights under a Gaussian of width ``sigma_s``; divided by the number of teeth that
  fit the window (longer periods are not favoured for having fewer) and weighted by a
  log-normal prior around ``prior_bpm`` (the octave human tempos most often sit in). The
  period follows the best candidate, smoothed in the log domain, and jumps only when another
  one has won by a margin twice in a row.
* **Phase.** The circular mean of the onsets' times modulo the period, each weighted by the
  square of its evidence (the kick and snare lead) and by recency (``recency_s``), anchors
  the beat grid.

:class:`BeatTracker` is the online object: :meth:`~BeatTracker.process` one onset at a
time (its own arrival time is "now"), :meth:`~BeatTracker.beats` the predicted beats in a
span; :func:`track_beats` is its offline twin: it feeds a whole onset array and collects the
beats the tracker would have predicted for each stretch between onsets before the next one
arrived, so it gives exactly the online beats. Bars are counted by ``beats_per_bar``
(4: GMD's grooves are mostly in 4/4; the downbeat itself is not detected).

Limits: no downbeat or meter detection; a tempo change settles in a few beats; before two
seconds of playing (or with fewer than six onsets) there is no estimate.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from livedrummer.kit.vocabulary import INSTRUMENTS

_BIN_S = 0.005  # pair distances are binned this finely

#: The share of the beat an instrument's onset carries (see the module docstring).
_BEAT_SHARE = {"kick": 1.0, "snare": 1.0, "hihat": 0.35, "ride": 0.35}


def instrument_weights() -> np.ndarray:
    """Evidence weight by instrument index (ONSET_DTYPE's ``instrument``)."""
    out = np.full(len(INSTRUMENTS), 0.6)
    for i, name in enumerate(INSTRUMENTS):
        for prefix, w in _BEAT_SHARE.items():
            if str(name).startswith(prefix):
                out[i] = w
    return out


@dataclass(frozen=True)
class BeatParams:
    window_s: float = 6.0
    min_bpm: float = 60.0
    max_bpm: float = 200.0
    prior_bpm: float = 105.0
    prior_width: float = 0.45  # log-normal width of the tempo prior (natural log units)
    sigma_s: float = 0.03  # width of a comb tooth
    recency_s: float = 4.0  # phase: an onset this old counts 1/e as much
    smooth: float = 0.3  # share of a new period estimate taken at each update
    beats_per_bar: int = 4


class BeatTracker:
    """See the module docstring."""

    def __init__(self, params: BeatParams | None = None) -> None:
        self.params = p = params or BeatParams()
        self._periods = 60.0 / np.geomspace(p.max_bpm, p.min_bpm, 160)
        lp = np.log(self._periods / (60.0 / p.prior_bpm))
        self._prior = np.exp(-0.5 * (lp / p.prior_width) ** 2)
        # the comb's teeth over a histogram of pair distances (bins of _BIN_S), per multiple
        centers = (np.arange(math.ceil(4.2 * self._periods.max() / _BIN_S)) + 0.5) * _BIN_S
        self._kernel = np.stack([
            np.exp(-0.5 * ((centers[None, :] - k * self._periods[:, None]) / p.sigma_s) ** 2)
            for k in (1, 2, 3, 4)
        ])  # fmt: skip
        self.reset()

    def reset(self) -> None:
        self._onsets: deque[tuple[float, float]] = deque()
        self.period_s: float | None = None
        self.phase_s = 0.0  # a beat time
        self._challenger: float | None = None
        self.first_s: float | None = None

    @property
    def bpm(self) -> float | None:
        return None if self.period_s is None else 60.0 / self.period_s

    def process(self, time_s: float, weight: float) -> None:
        """One onset (its time is now) of evidence ``weight``."""
        p = self.params
        if self.first_s is None:
            self.first_s = time_s
        q = self._onsets
        q.append((time_s, weight))
        while q and q[0][0] < time_s - p.window_s:
            q.popleft()
        if len(q) < 6 or time_s - self.first_s < 2.0:
            return
        t = np.array([x for x, _ in q])
        w = np.array([y for _, y in q])
        self._update_period(t, w)
        self._update_phase(t, w, time_s)

    def _update_period(self, t: np.ndarray, w: np.ndarray) -> None:
        p = self.params
        d = (t[None, :] - t[:, None]).ravel()
        ww = (w[None, :] * w[:, None]).ravel()
        keep = (d > 0.15) & (d < _BIN_S * self._kernel.shape[2])
        hist = np.bincount((d[keep] / _BIN_S).astype(np.int64), ww[keep],
                           self._kernel.shape[2])  # fmt: skip
        span = max(float(t[-1] - t[0]), 1e-3)
        score = np.zeros(self._periods.size)
        for k in range(self._kernel.shape[0]):
            fits = span > (k + 1) * self._periods
            score += np.where(fits, self._kernel[k] @ hist, 0.0) / (k + 1)
        score *= self._prior
        best = float(self._periods[int(np.argmax(score))])
        if self.period_s is None:
            self.period_s = best
            return
        ratio = best / self.period_s
        if abs(math.log(ratio)) < 0.08:
            self.period_s = math.exp((1 - p.smooth) * math.log(self.period_s)
                                     + p.smooth * math.log(best))  # fmt: skip
            self._challenger = None
        elif self._challenger is not None and abs(math.log(best / self._challenger)) < 0.08:
            self.period_s, self._challenger = best, None  # it won twice in a row
        else:
            self._challenger = best

    def _update_phase(self, t: np.ndarray, w: np.ndarray, now: float) -> None:
        period = self.period_s
        if period is None:
            return
        r = w * w * np.exp(-(now - t) / self.params.recency_s)
        z = np.sum(r * np.exp(2j * np.pi * t / period))
        if abs(z) == 0:
            return
        self.phase_s = float(np.angle(z)) / (2 * np.pi) * period

    def beats(self, lo_s: float, hi_s: float) -> np.ndarray:
        """The predicted beats in ``[lo_s, hi_s)`` (none before the first estimate)."""
        if self.period_s is None or hi_s <= lo_s:
            return np.zeros(0)
        k0 = math.ceil((lo_s - self.phase_s) / self.period_s)
        k1 = math.ceil((hi_s - self.phase_s) / self.period_s)
        return self.phase_s + self.period_s * np.arange(k0, k1)


def onset_weights(onsets: np.ndarray) -> np.ndarray:
    """Each onset's evidence: velocity (0..1) times its instrument's beat share."""
    share = instrument_weights()
    inst = np.clip(onsets["instrument"].astype(np.int64), 0, share.size - 1)
    out: np.ndarray = onsets["velocity"].astype(np.float64) / 127.0 * share[inst]
    return out


def track_beats(times: np.ndarray, weights: np.ndarray, end_s: float,
                params: BeatParams | None = None) -> np.ndarray:  # fmt: skip
    """The offline twin (see the module docstring): the beats a :class:`BeatTracker` fed
    these onsets one at a time predicts, each from what it had heard by then, up to
    ``end_s``."""
    tracker = BeatTracker(params)
    out: list[np.ndarray] = []
    for i in range(times.size):
        tracker.process(float(times[i]), float(weights[i]))
        nxt = float(times[i + 1]) if i + 1 < times.size else end_s
        out.append(tracker.beats(float(times[i]), nxt))
    return np.concatenate(out) if out else np.zeros(0)


def beat_accuracy(detected: np.ndarray, reference: np.ndarray, from_s: float,
                  tolerance_s: float = 0.07) -> float:  # fmt: skip
    """The fraction of reference beats at or after ``from_s`` with a detected beat within
    ``tolerance_s``."""
    ref = reference[reference >= from_s]
    if ref.size == 0 or detected.size == 0:
        return 0.0
    det = np.sort(detected)
    i = np.clip(np.searchsorted(det, ref), 1, det.size - 1)
    near = np.minimum(np.abs(det[i] - ref), np.abs(det[i - 1] - ref))
    return float(np.mean(near <= tolerance_s))
