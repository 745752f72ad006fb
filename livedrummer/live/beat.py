"""An online beat tracker on live drum onsets: tempo, beat phase and bars, causally.

Method (our own, after the published trackers' stages: a tempo from the periodicity of recent
onsets, as BTrack's comb-filtered autocorrelation under a tempo prior; then the phase of a
beat grid, as BTrack's cumulative score and madmom's online tracking; bars from where the
kick and the snare fall):

* **Evidence.** Each onset weighs its velocity times its instrument's share of the beat:
  kick and snare mark beats and backbeats (1.0), cymbals and toms less (0.6), the hi-hat's
  and ride's steady subdivisions least (0.35), so a busy hi-hat does not pull the tempo to
  eighths. Only the last ``window_s`` seconds count.
* **Tempo.** For each candidate period (log-spaced, ``min_bpm``..``max_bpm``), a comb score:
  every pair of onsets whose distance lies near a half multiple of the period (1/2 .. 4)
  adds the product of their weights under a Gaussian of width ``sigma_s``; whole multiples
  weigh 1, odd halves ``half_share`` (a true beat has its eighths, a syncopation's 3:4
  ghost period has none), each tooth less the further out it is; divided by the weight of the
  teeth that fit the window and weighted by a log-normal prior around ``prior_bpm``. The
  period follows the best candidate, smoothed in the log domain, and jumps only when another
  one has won by a margin twice in a row.
* **Phase.** Beat grids shifted from the current one by 1/64 of a period are scored: each
  onset (evidence squared, kicks and crashes ``1 + kick_boost`` times more, recent ones more:
  ``recency_s``) counts for a grid under a Gaussian of its distance to the grid's nearest
  beat and, ``offbeat`` times, against it near the grid's off-beats, so a syncopated kick or
  an off-beat hi-hat does not pull the grid onto the "and". Where the kick is pushed onto the
  "and"s against a snare backbeat, the kicks win that score: the best grid then moves half a
  beat when the snares on its beats outweigh those on its rival's by ``backbeat`` of all
  their weight and its beats keep ``backbeat_kick`` of the kick's (2 and 4 with a kick on
  1, not a dembow's or merengue's off-beat snares). A small shift is followed
  (smoothed); a large one only once it has won by ``switch`` for ``switch_beats`` beats. A
  correction never repeats or skips the beat at hand (:meth:`BeatTracker._keep_heard`):
  every beat is given once, so a service polling the tracker sees no jump.
* **Bars.** A kick or a crash near a beat is evidence (decaying over ``downbeat_decay_s``)
  for that beat starting a bar, a snare (the backbeat) against; the bar's first beat is the
  one with the most evidence plus half its middle beat's (``beats_per_bar``, 4 by default).
  Bars are numbered as they are given, one more each (:meth:`BeatTracker.bars`): a corrected
  downbeat stretches or moves a bar, it never skips a number a cue may wait for.

:class:`BeatTracker` is the online object: :meth:`~BeatTracker.process` one onset at a
time (its own arrival time is "now"), :meth:`~BeatTracker.beats` the predicted beats in a
span, :meth:`~BeatTracker.bars` the bar starts and their numbers; :func:`track_beats` is its
offline twin: it feeds a whole onset array and collects the beats the tracker would have
predicted for each stretch between onsets before the next one arrived, so it gives exactly
the online beats. The constants were tuned on GMD's train and validation grooves
(``livedrummer bench beats --split test`` measures on the others).

Limits: the meter is not detected (``beats_per_bar``); tempos above ``max_bpm`` are followed
at half speed; a tempo change settles in a few beats; before two seconds of playing (or with
fewer than six onsets) there is no estimate; about 0.4 ms of CPU per onset. Only the newest
``max_onsets`` (256: 10 s of any real playing) are kept: the tempo's pair histogram is quadratic
in them, and a flood of 1,000 notes a second made each update cost 50 ms before the cap. The
histogram is kept up to date as onsets come and go (their pairs with the others added or
taken out: linear), and while the onsets kept span less than the longest tooth the comb of
the teeth that fit is cached until they change: at 100 notes/s, where both held, an update
cost 5-11 ms (the pairs' square and the 13 MB kernel read tooth by tooth for every onset) and
now costs about 1.5, most of it the phase; the tracker's state after every onset is the same
as before on the demo groove and at 100 notes/s (floating-point sums in another order).
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
#: An onset's sign as evidence for a bar's first beat (see :func:`downbeat_weights`).
_DOWNBEAT_SIGN = {"kick": 1.0, "crash": 0.5, "snare": -1.0}


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
    window_s: float = 10.0
    min_bpm: float = 60.0
    max_bpm: float = 230.0
    prior_bpm: float = 120.0
    prior_width: float = 0.45  # log-normal width of the tempo prior (natural log units)
    sigma_s: float = 0.025  # width of a comb tooth
    half_share: float = 0.7  # weight of the comb's teeth at odd half periods
    recency_s: float = 8.0  # phase: an onset this old counts 1/e as much
    phase_sigma: float = 0.06  # phase: an onset's reach, in periods
    offbeat: float = 0.3  # phase: how much an onset half a period off counts against
    switch: float = 1.15  # a new phase or downbeat must beat the current one by this factor
    switch_beats: float = 1.0  # ... for this many beats in a row (phase)
    smooth: float = 0.3  # share of a new period or phase estimate taken at each update
    kick_boost: float = 2.0  # phase: a kick (or crash) weighs (1 + this) times more
    backbeat: float = 0.5  # phase: the snare's margin (share of its weight) for the half-shift
    backbeat_kick: float = 0.1  # ... whose beats must keep this share of the kick's weight
    downbeat_decay_s: float = 8.0  # downbeat evidence this old counts 1/e as much
    beats_per_bar: int = 4
    max_onsets: int = 256  # the newest onsets kept (a flood must not make each update O(n^2))


_PHASES = 64  # candidate beat phases per period
#: A beat this close after an onset may have been given already to a service polling the
#: tracker at 100 Hz or faster: a correction does not move it (see BeatTracker._keep_heard).
_HELD_S = 0.012


class BeatTracker:
    """See the module docstring."""

    def __init__(self, params: BeatParams | None = None) -> None:
        self.params = p = params or BeatParams()
        self._periods = 60.0 / np.geomspace(p.max_bpm, p.min_bpm, 160)
        lp = np.log(self._periods / (60.0 / p.prior_bpm))
        self._prior = np.exp(-0.5 * (lp / p.prior_width) ** 2)
        # the comb's teeth over a histogram of pair distances (bins of _BIN_S), at each half
        # multiple m/2 of the period, m = 1..8: whole multiples weigh 1, odd halves half_share
        centers = (np.arange(math.ceil(4.2 * self._periods.max() / _BIN_S)) + 0.5) * _BIN_S
        self._teeth = np.arange(1, 9) / 2.0
        self._tooth_w = np.where(np.arange(1, 9) % 2 == 0, 1.0, p.half_share) / np.sqrt(self._teeth)
        self._kernel = np.stack(
            [
                np.exp(-0.5 * ((centers[None, :] - m * self._periods[:, None]) / p.sigma_s) ** 2)
                for m in self._teeth
            ]
        )
        self._comb = np.tensordot(self._tooth_w, self._kernel, axes=1)  # all teeth at once
        self._comb_norm = float(np.sum(self._tooth_w))
        self._fit = np.full(self._periods.size, -1)  # teeth that fit each row of the comb below
        self._fit_comb = np.zeros_like(self._comb)
        self._fit_norm = np.zeros(self._periods.size)
        self._offsets = (np.arange(_PHASES) / _PHASES + 0.5) % 1.0 - 0.5  # in periods
        self.reset()

    def reset(self) -> None:
        self._onsets: deque[tuple[float, float, float]] = deque()
        self._hist = np.zeros(self._kernel.shape[2])  # weights of the onsets' pair distances
        self.period_s: float | None = None
        self.phase_s = 0.0  # a beat time: the latest beat at or before the last onset
        self._beat_index = 0  # the beat at phase_s, counted from the first estimate's
        self._challenger: float | None = None
        self._phase_challenger: tuple[float, float] | None = None  # (shift, since)
        self._bar_evidence = np.zeros(max(self.params.beats_per_bar, 1))
        self._bar_time = 0.0
        self.downbeat = 0  # beats whose index is this modulo beats_per_bar start a bar
        self._last_bar: tuple[float, int] | None = None  # the latest bar start given, its number
        self.first_s: float | None = None

    @property
    def bpm(self) -> float | None:
        return None if self.period_s is None else 60.0 / self.period_s

    def process(self, time_s: float, weight: float, downbeat: float = 0.0) -> None:
        """One onset (its time is now) of evidence ``weight``; ``downbeat``: its evidence for
        a bar's first beat (positive for a kick, negative for a snare; see
        :func:`downbeat_weights`)."""
        p = self.params
        if self.first_s is None:
            self.first_s = time_s
        q = self._onsets
        self._pair_in((time_s, weight), q, 1.0)
        q.append((time_s, weight, downbeat))
        while q and (q[0][0] < time_s - p.window_s or len(q) > p.max_onsets):
            self._pair_in(q.popleft()[:2], q, -1.0)
        if len(q) < 6 or time_s - self.first_s < 2.0:
            return
        t = np.array([x[0] for x in q])
        w = np.array([x[1] for x in q])
        db = np.array([x[2] for x in q])
        lead = 1.0 + p.kick_boost * np.maximum(db, 0.0)
        fresh = self.period_s is None
        before = None if fresh else self._nearest(time_s)
        self._update_period(t)
        self._update_phase(t, w * np.sqrt(lead), time_s, fresh, db)
        if before is not None:
            self._keep_heard(before, time_s)
        if downbeat != 0.0:
            self._update_downbeat(time_s, downbeat)

    def _pair_in(
        self, onset: tuple[float, float], others: deque[tuple[float, float, float]], sign: float
    ) -> None:
        """The pairs of ``onset`` (time, weight) with each of ``others`` added to the pair
        histogram (``sign`` 1) or taken out of it (-1): a pair counts once, in the bin of its
        distance, when that lies between 0.1 s and the histogram's end. Kept up to date onset
        by onset (linear in the onsets kept), it is the histogram of all their pairs, which
        costs their square to rebuild (5 ms per onset at 100 notes/s)."""
        if not others:
            return
        arr = np.array(others)
        d = np.abs(arr[:, 0] - onset[0])
        keep = (d > 0.1) & (d < _BIN_S * self._hist.size)
        if keep.any():
            self._hist += sign * np.bincount(
                (d[keep] / _BIN_S).astype(np.int64), arr[keep, 1] * onset[1], self._hist.size
            )

    def _partial_comb(self, span: float) -> tuple[np.ndarray, np.ndarray]:
        """The comb of the teeth that fit ``span`` (per period: a tooth at ``m`` periods fits
        when ``m`` periods are shorter than the span) and its norm, for a window shorter than
        the longest tooth. A period's row is rebuilt only when the teeth that fit it change
        (while the span grows, a few rows an onset; a steady fast stream's span stays the
        same), so each update is one product, as with every tooth (the teeth one by one read
        the whole kernel, 13 MB, for every onset)."""
        fit = np.sum(span > self._teeth[:, None] * self._periods[None, :], axis=0)
        changed = np.flatnonzero(fit != self._fit)
        if changed.size:
            on = np.arange(self._teeth.size)[:, None] < fit[None, changed]  # teeth x rows
            w = np.where(on, self._tooth_w[:, None], 0.0)
            self._fit_comb[changed] = np.einsum("kp,kpb->pb", w, self._kernel[:, changed])
            self._fit_norm[changed] = w.sum(axis=0)
            self._fit[changed] = fit[changed]
        return self._fit_comb, self._fit_norm

    def _update_period(self, t: np.ndarray) -> None:
        p = self.params
        hist = self._hist
        span = max(float(t[-1] - t[0]), 1e-3)
        if span > self._teeth[-1] * self._periods[-1]:  # every tooth fits: one product
            score: np.ndarray = self._comb @ hist
            norm: np.ndarray = np.full(self._periods.size, self._comb_norm)
        else:
            comb, norm = self._partial_comb(span)
            score = comb @ hist
        score = score / np.maximum(norm, 1e-9) * self._prior
        best = float(self._periods[int(np.argmax(score))])
        if self.period_s is None:
            self.period_s = best
            return
        ratio = best / self.period_s
        if abs(math.log(ratio)) < 0.08:
            self.period_s = math.exp(
                (1 - p.smooth) * math.log(self.period_s) + p.smooth * math.log(best)
            )
            self._challenger = None
        elif self._challenger is not None and abs(math.log(best / self._challenger)) < 0.08:
            self.period_s, self._challenger = best, None  # it won twice in a row
        else:
            self._challenger = best

    def _update_phase(
        self, t: np.ndarray, w: np.ndarray, now: float, fresh: bool, db: np.ndarray
    ) -> None:
        """Score beat grids shifted from the current one by a fraction of a period: onsets on
        a grid's beats count for it, onsets half a period off against it (so a syncopated kick
        or an off-beat hi-hat does not pull the grid onto the off-beats); a regular snare
        backbeat may then move the best grid by half a beat (:meth:`_backbeat`)."""
        p = self.params
        period = self.period_s
        if period is None:
            return
        r = w * w * np.exp(-(now - t) / p.recency_s)
        u = ((t - self.phase_s) / period) % 1.0  # each onset's place in the current grid
        diff = (u[None, :] - self._offsets[:, None] + 0.5) % 1.0 - 0.5
        off = (diff + 1.0) % 1.0 - 0.5  # the distance to the shifted grid's off-beats
        g = np.exp(-0.5 * (diff / p.phase_sigma) ** 2) - p.offbeat * np.exp(
            -0.5 * (off / p.phase_sigma) ** 2
        )
        score = g @ r
        j = int(np.argmax(score))
        flip = self._backbeat(diff, j, db, np.exp(-(now - t) / p.recency_s))
        if flip:
            j = (j + _PHASES // 2) % _PHASES
        shift = float(self._offsets[j])
        if fresh:
            self.phase_s += shift * period
        elif abs(shift) < 0.1:
            self.phase_s += p.smooth * shift * period
            self._phase_challenger = None
        else:
            here = float(score[0])  # offsets[0] is the current grid
            wins = flip or (score[j] > p.switch * here if here > 0 else score[j] > here)
            rival = self._phase_challenger
            if wins and rival is not None and abs((shift - rival[0] + 0.5) % 1.0 - 0.5) < 0.1:
                if now - rival[1] >= p.switch_beats * period:  # it has won for a while
                    self.phase_s += shift * period
                    self._phase_challenger = None
            else:
                self._phase_challenger = (shift, now) if wins else None
        n = math.floor((now - self.phase_s) / period)
        self.phase_s += n * period
        self._beat_index = 0 if fresh else self._beat_index + n

    def _backbeat(self, diff: np.ndarray, j: int, db: np.ndarray, recency: np.ndarray) -> bool:
        """Whether the grid half a beat from grid ``j`` is the beat: the snares (velocity
        squared, recent ones more) on its beats outweigh those on ``j``'s by ``backbeat`` of
        all their weight (a regular backbeat on 2 and 4, where a kick pushed onto the "and"s
        had pulled the grid there), and its beats keep ``backbeat_kick`` of the kick's weight
        (a kick on 1: not a dembow or a merengue, whose snares fall off their beat)."""
        p = self.params
        snare = np.maximum(-db, 0.0) ** 2 * recency
        kick = np.maximum(db, 0.0) ** 2 * recency
        total = float(np.sum(snare))
        if total <= 0.0:
            return False
        k = (j + _PHASES // 2) % _PHASES
        near = np.exp(-0.5 * (diff[[j, k]] / p.phase_sigma) ** 2)
        on = near @ snare
        return bool(
            on[1] - on[0] > p.backbeat * total
            and near[1] @ kick >= p.backbeat_kick * float(np.sum(kick))
        )

    def _nearest(self, t: float) -> float:
        assert self.period_s is not None
        return self.phase_s + self.period_s * round((t - self.phase_s) / self.period_s)

    def _keep_heard(self, before: float, now: float) -> None:
        """A corrected grid neither repeats nor skips the beat at hand: if the correction
        would carry that beat across the onset's time (or within ``_HELD_S`` after it, a
        service's tick, which may have given it already), it waits for the next onset: the
        beat stays where it was, so every beat is given once."""
        assert self.period_s is not None
        after = self._nearest(before)  # the same beat on the corrected grid
        past = before < now and after < now
        ahead = before >= now + _HELD_S and after >= now + _HELD_S
        if past or ahead:
            return
        self.phase_s += before - after
        n = math.floor((now - self.phase_s) / self.period_s)
        self.phase_s += n * self.period_s
        self._beat_index += n

    def _update_downbeat(self, now: float, evidence: float) -> None:
        """Kick near a beat: evidence for that beat starting a bar; snare: against."""
        p = self.params
        if self.period_s is None or p.beats_per_bar < 2:
            return
        k = round((now - self.phase_s) / self.period_s)
        if abs(now - self.phase_s - k * self.period_s) > 0.15 * self.period_s:
            return
        self._bar_evidence *= math.exp(-(now - self._bar_time) / p.downbeat_decay_s)
        self._bar_time = now
        self._bar_evidence[(self._beat_index + k) % p.beats_per_bar] += evidence
        ev = self._bar_evidence
        # a bar's first beat: the most kick and least snare, its middle beat (3 in 4/4) half so
        score = ev + 0.5 * np.roll(ev, -(p.beats_per_bar // 2))
        best = int(np.argmax(score))
        if (
            best != self.downbeat
            and score[best]
            > score[self.downbeat] + abs(score[self.downbeat]) * (p.switch - 1.0) + 1e-9
        ):
            self.downbeat = best

    def beats(self, lo_s: float, hi_s: float) -> np.ndarray:
        """The predicted beats in ``[lo_s, hi_s)`` (none before the first estimate)."""
        if self.period_s is None or hi_s <= lo_s:
            return np.zeros(0)
        k0 = math.ceil((lo_s - self.phase_s) / self.period_s)
        k1 = math.ceil((hi_s - self.phase_s) / self.period_s)
        return self.phase_s + self.period_s * np.arange(k0, k1)

    def bars(self, lo_s: float, hi_s: float) -> list[tuple[float, int]]:
        """The predicted bar starts in ``[lo_s, hi_s)``: (time, bar number). Bar 1 is the
        first bar to start after the tracker's first estimate (its first downbeat). Numbers
        count the bar starts given, not the beats: a corrected downbeat that moves a start by
        under half a bar gives it again with its number, and one that makes a bar longer (up
        to 7 beats in 4/4, where the correction came after the start it moved had passed)
        gives the next start the next number; a number is skipped only when the span asked
        for left out whole bars (a caller that stalled). So a cue at "bar 6" plays on the
        sixth bar heard, whatever the tracker corrected in between."""
        if self.period_s is None or hi_s <= lo_s:
            return []
        n = self.params.beats_per_bar
        k0 = math.ceil((lo_s - self.phase_s) / self.period_s)
        k1 = math.ceil((hi_s - self.phase_s) / self.period_s)
        out = []
        for k in range(k0, k1):
            index = self._beat_index + k - self.downbeat
            if index >= 0 and index % n == 0:
                t = self.phase_s + k * self.period_s
                out.append((t, self._bar_number(t, index // n + 1, n * self.period_s)))
        return out

    def _bar_number(self, t: float, counted: int, bar_s: float) -> int:
        """The number of the bar starting at ``t`` (see :meth:`bars`); ``counted``: its
        number from the beat count, taken for the first bar given."""
        if self._last_bar is None:
            self._last_bar = (t, counted)
            return counted
        last_t, last_n = self._last_bar
        gap = (t - last_t) / bar_s
        if gap < -0.5:  # an earlier bar asked for again: numbered back from the latest
            return max(1, last_n + round(gap))
        if gap < 0.5:
            number = last_n  # the same start, moved
        elif gap < 1.875:
            number = last_n + 1  # the next bar, however a correction stretched this one
        else:
            number = last_n + round(gap)
        self._last_bar = (t, number)
        return number


def onset_weights(onsets: np.ndarray) -> np.ndarray:
    """Each onset's evidence: velocity (0..1) times its instrument's beat share."""
    share = instrument_weights()
    inst = np.clip(onsets["instrument"].astype(np.int64), 0, share.size - 1)
    out: np.ndarray = onsets["velocity"].astype(np.float64) / 127.0 * share[inst]
    return out


def downbeat_weights(onsets: np.ndarray) -> np.ndarray:
    """Each onset's evidence for a bar's first beat: a kick's velocity (0..1), a crash's half
    of it, minus a snare's (the backbeat); others none."""
    sign = np.zeros(len(INSTRUMENTS))
    for i, name in enumerate(INSTRUMENTS):
        for prefix, s in _DOWNBEAT_SIGN.items():
            if str(name).startswith(prefix):
                sign[i] = s
    inst = np.clip(onsets["instrument"].astype(np.int64), 0, sign.size - 1)
    out: np.ndarray = onsets["velocity"].astype(np.float64) / 127.0 * sign[inst]
    return out


def track_beats(
    times: np.ndarray,
    weights: np.ndarray,
    end_s: float,
    params: BeatParams | None = None,
    downbeats: np.ndarray | None = None,
) -> np.ndarray:
    """The offline twin (see the module docstring): the beats a :class:`BeatTracker` fed
    these onsets one at a time predicts, each from what it had heard by then, up to
    ``end_s``."""
    tracker = BeatTracker(params)
    out: list[np.ndarray] = []
    for i in range(times.size):
        tracker.process(
            float(times[i]), float(weights[i]), 0.0 if downbeats is None else float(downbeats[i])
        )
        nxt = float(times[i + 1]) if i + 1 < times.size else end_s
        out.append(tracker.beats(float(times[i]), nxt))
    return np.concatenate(out) if out else np.zeros(0)


def beat_accuracy(
    detected: np.ndarray, reference: np.ndarray, from_s: float, tolerance_s: float = 0.07
) -> float:
    """The fraction of reference beats at or after ``from_s`` with a detected beat within
    ``tolerance_s``."""
    ref = reference[reference >= from_s]
    if ref.size == 0 or detected.size == 0:
        return 0.0
    det = np.sort(detected)
    i = np.clip(np.searchsorted(det, ref), 1, det.size - 1)
    near = np.minimum(np.abs(det[i] - ref), np.abs(det[i - 1] - ref))
    return float(np.mean(near <= tolerance_s))


def beat_precision(
    detected: np.ndarray, reference: np.ndarray, from_s: float, tolerance_s: float = 0.07
) -> float:
    """The fraction of detected beats from ``from_s`` to the last reference beat with a
    reference beat within ``tolerance_s``: :func:`beat_accuracy`'s other half (a tracker
    at double tempo matches every reference beat, and half its own beats are extra)."""
    if reference.size == 0:
        return 0.0
    det = detected[(detected >= from_s) & (detected <= reference[-1] + tolerance_s)]
    return beat_accuracy(reference, det, -math.inf, tolerance_s) if det.size else 0.0
