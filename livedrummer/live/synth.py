"""The online stroke synthesizer: onsets in, one at a time; pose samples out, on show time.

Why this shape. The body's :func:`~livedrummer.body.animation.animate` builds a whole
performance's curves at once (about 20 ms whatever the length, for a few seconds of notes),
so the live synth does not re-implement strokes: it keeps a sliding window of notes and
re-runs the body over that window whenever the set of notes changes, then samples the curves
only for the times it has not published yet. Three timelines meet here:

* *performance time* is the onset's own time on the shared clock (its arrival stamp);
* the online sticking (:class:`~livedrummer.sticking.online.OnlineSticker`) commits a hand
  note ``L`` (lookahead) after its onset, so at clock time ``now`` every note up to
  ``now - L`` is decided: that is how far the synth samples (its *horizon*);
* *show time* is performance time + ``D``: the display shows the pose sampled at ``t`` when
  the shared clock reads ``t + D``, and a contact sample is always included at exactly each
  onset + D.

Provisional poses (the default; ``SynthParams.provisional``). Waiting for the sticking's
decision would publish a hit's contact only ``L`` after the hit (``D - L`` before it is seen:
no slack at all with the default ``D = L``). Instead the synth samples up to ``now``: an
arrived, undecided note joins the window with its provisional hand (what the online
sticking's cheapest path so far gives it: its decision in 99.5 % of cases), so its stroke
goes out as soon as the window is re-animated. Everything published past the committed
horizon ``now - L`` is provisional: when a decision, an arrival or a dropped guess changes
the window, the synth re-sends from the previous committed horizon (the display's
:class:`~livedrummer.live.track.PoseTrack` lets a batch replace the samples it covers),
cross-fading into the new curves before the next contact. With ``provisional=False``
samples go out only up to ``now + D - L``, never twice.

Quick contacts. Re-animating the window takes about 10-20 ms; a hit does not wait for it.
:meth:`process` solves every arriving hit's contact pose at once: the body as last sampled
near the onset, with the striking limb's IK onto its piece (its decided limb, or the
provisional one above); :meth:`take_quick` hands it out (with the held samples since the
last batch, so the display's track has no hole) and the service publishes it before
re-animating; the re-animated curves replace it a moment later with the whole stroke. Hits
that arrive together are solved in one call (:func:`~livedrummer.live.quick.quick_contact`,
a pure function of a read-only :meth:`quick_state` snapshot).

Answering during a re-animation. :attr:`pause`, when set, is called between the steps of a
re-animation and of the sampling that follows (a few milliseconds apart at most): the
service reads its socket there, so a hit that arrives meanwhile gets its contact out then,
not after the re-animation. Everything a re-animation reads was taken before it started, and
the samples held ahead are swapped only when the new ones are complete; a batch built from
curves that lack a hit answered meanwhile still carries that hit's quick contact.

Prediction. A :class:`~livedrummer.live.predict.HandPredictor` places at most one *guess*
note per hand at its expected next onset; the guess takes part in the animation (so the
upswing starts on time) but its contact is never shown: when the horizon gets within
``guard_s`` of it and no onset has arrived near it, it is dropped and the body settles back;
when an onset has arrived (its limb still pending), the guess moves to that exact time and is
replaced by the committed note when the horizon reaches it. With ``D > L`` (or provisional
poses) arrived, pending notes also join the window with a guessed hand. Whenever the window's
notes change, the new curves are cross-faded from the old ones, and the fade always ends at
the next contact, so a surprise hit strikes fast and every contact lands exactly.

Idle. With no notes the torso still sways on a slow "breathing" beat (the body's sway keyed on
``idle_period_s``), so the drummer never freezes.

Limits: re-animation costs 10-20 ms each time the window changes (about two times per note
of a groove: arrival, a new or dropped guess; old notes leave half a window at a time, and
a moving pedal alone re-animates at most every ``control_every_s``), so at 1,000 notes/s
most of the time goes to quick contacts and the strokes between them are re-animated only a
few times a second; a quick contact with a wrong provisional hand shows that hand striking
until the decision re-animates; the cross-fade blends joint positions and quaternions
linearly (bones may shorten by a few mm mid-fade); hi-hat openness comes from the onsets and
the pedal controller of the window only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np

from livedrummer.body.animation import ClearanceMemo, animate, hihat_openness
from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import Rig
from livedrummer.body.strokes import StrokeParams
from livedrummer.events import CONTROL_DTYPE, ONSET_DTYPE
from livedrummer.live.predict import Guess, HandPredictor
from livedrummer.live.quick import (
    Curves,
    QuickState,
    quick_contact,
    sample_curves,
)
from livedrummer.sticking.online import Decision, OnlineSticker
from livedrummer.sticking.result import NOT_PLAYED, Sticking
from livedrummer.vocabulary import INSTRUMENTS

SENT_KEEP_S = 0.25  # published samples kept as the body quick contacts start from


@dataclass(frozen=True)
class SynthParams:
    lookahead_s: float = 0.030  # L: the sticking commits a hand note this long after its onset
    delay_s: float = 0.030  # D: the avatar is shown this long behind the sound
    rate_hz: float = 240.0  # pose samples per second of show time
    window_s: float = 1.0  # notes older than this (behind the horizon) leave the window
    predict: bool = True
    blend_s: float = 0.06  # longest cross-fade between old and new curves
    guard_s: float = 0.025  # a guess is dropped this long before its contact
    idle_period_s: float = 4.0  # "breathing" sway period when nothing is played
    chunk_s: float = 0.05  # sample this far ahead of the horizon at once (dropped on change)
    epoch_s: float = 4.0  # the torso's beat keys are rebuilt at least this often
    provisional: bool = True  # publish up to now with pending notes' guessed hands; resend
    control_every_s: float = 0.1  # pedal (CC4) changes alone re-animate at most this often

    def __post_init__(self) -> None:
        if not 0.0 <= self.lookahead_s <= self.delay_s:
            raise ValueError(
                f"need 0 <= lookahead ({self.lookahead_s}) <= delay ({self.delay_s}): a note must "
                "be decided before its contact is shown"
            )
        if not self.rate_hz > 0 or not self.window_s > 0:
            raise ValueError(f"rate {self.rate_hz} and window {self.window_s} must be > 0")


@dataclass(frozen=True)
class PoseBatch:
    """Pose samples: ``show_s`` (float64 show times) and the matching pose records, whose
    ``time_s`` field holds the performance time relative to ``show_s[0] - D`` (float32 cannot
    hold clock times to the millisecond)."""

    show_s: np.ndarray
    rows: np.ndarray


@dataclass
class _Note:
    row: np.ndarray  # one ONSET_DTYPE record (0-d array)
    index: int  # its position in the stream (the sticking's index)
    limb: int = NOT_PLAYED
    piece: int = -1
    decided: bool = False
    hand: bool = False


class LiveSynth:
    """See the module docstring. Feed :meth:`process` and :meth:`control`; call
    :meth:`poses_until` with the clock's now as often as poses should go out."""

    def __init__(
        self,
        rig: Rig,
        params: SynthParams | None = None,
        *,
        strokes: StrokeParams | None = None,
        cc_open: np.ndarray | None = None,
    ) -> None:
        self.rig = rig
        self.params = params or SynthParams()
        self.strokes = strokes or StrokeParams()
        self.cc_open = cc_open
        self.dtype = pose_dtype(len(rig.kit.pieces))
        self.sticker = OnlineSticker(rig.kit, self.params.lookahead_s)
        self.predictor = HandPredictor()
        #: called between the steps of a re-animation and of sampling (a few ms at most
        #: apart): a service answers arriving hits there with :meth:`process` and
        #: :meth:`take_quick` (see the module docstring)
        self.pause: Callable[[], None] | None = None
        self.reset()

    def reset(self) -> None:
        self.sticker.reset()
        self.predictor.reset()
        self._notes: list[_Note] = []  # every note since the window start, by stream index
        self._first = 0  # stream index of self._notes[0]
        self._controls: list[np.ndarray] = []
        self._guesses: dict[int, Guess] = {}
        self._horizon: float | None = None  # last sampled performance time
        self._final = -math.inf  # the committed horizon (now - L) at the last call
        self._refreshed_at = -math.inf  # horizon of the last re-animation
        self._curves: Curves | None = None
        self._clearance: ClearanceMemo = {}  # the clearance search's settings, window to window
        self._old: Curves | None = None
        self._fade = (0.0, 0.0)  # start, length (performance time)
        self.animations = 0  # how many times the body was re-run (for benchmarks)
        self.quick_contacts = 0  # hits whose contact went out before re-animating
        self._quick: list[np.ndarray] = []  # onset times of quick contacts not yet taken
        self._quick_end = -math.inf  # the last onset time a quick batch reached
        self._struck: dict[float, np.ndarray] = {}  # quick contacts the curves do not have yet
        self._cache_t = np.zeros(0)  # samples of the current curves ahead of the horizon
        self._cache_rows = np.zeros(0, self.dtype)
        self._sent_t = np.zeros(0)  # samples published lately (the body a quick contact uses)
        self._sent_rows = np.zeros(0, self.dtype)

    # -- input ---------------------------------------------------------------------------------

    def process(self, rows: np.ndarray | np.void, quick: bool = True) -> None:
        """Onsets (one ONSET_DTYPE record or an array of them, in arrival order; their times
        are the arrivals on the shared clock). ``quick``: also prepare their quick contacts
        (:meth:`take_quick`) with their decided or provisional limbs, all in one go (only with
        provisional poses: without, nothing goes out before the decision)."""
        recs = np.atleast_1d(np.asarray(rows, dtype=ONSET_DTYPE))
        notes = []
        for rec in recs:
            note = _Note(np.array(rec, dtype=ONSET_DTYPE), self._first + len(self._notes))
            self._notes.append(note)
            notes.append(note)
            self._apply(self.sticker.process(cast(np.void, note.row[()])))
        if not (quick and self.params.provisional and notes):
            return
        played = [(n.limb, n.piece) if n.decided else self._provisional_limb(n) for n in notes]
        limbs = np.array([li for li, _ in played], dtype=np.int64)
        pieces = np.array([pi for _, pi in played], dtype=np.int64)
        times, out = quick_contact(self.quick_state(), recs, limbs, pieces)
        if times.size:
            self._struck.update(zip(times.tolist(), out, strict=True))
            self._quick.append(times)
            self.quick_contacts += int(np.sum((limbs >= 0) & (pieces >= 0)))

    def quick_state(self) -> QuickState:
        """A read-only copy for :func:`~livedrummer.live.quick.quick_contact`."""
        return QuickState(self.rig, self.dtype, self._curves, self._old, self._fade,
                          *self._held(), dict(self._struck))  # fmt: skip

    def take_quick(self) -> PoseBatch:
        """Quick contacts of the hits that arrived since the last call, to publish at once,
        ahead of :meth:`poses_until`: one batch, ascending, from the end of what was published
        (or the first contact) to the last contact, the samples between filled in from what
        was published and is held ahead (a batch replaces the range it covers: contacts
        alone would hide those; without the held ones, a synth busy re-animating would leave
        the display a hole before a hit).
        For a time sent twice (a chord completed) the last contact wins."""
        if not self._quick:
            return self._batch(np.zeros(0), np.zeros(0, self.dtype))
        lo = min(float(times.min()) for times in self._quick)
        hi = max(float(times.max()) for times in self._quick)
        self._quick.clear()
        # from the end of what was published (grid samples, or the last quick batch) on
        sent_end = max(self._horizon if self._horizon is not None else -math.inf, self._quick_end)
        lo = min(lo, sent_end)
        self._quick_end = max(self._quick_end, hi)
        held_t, held = self._held()
        fill = (held_t > lo) & (held_t <= hi)
        # with every quick contact the curves lack in the range, this one's and earlier ones
        # (a batch replaces its range: leaving one out would erase it from the display)
        return self._batch(*self._with_struck(held_t[fill], held[fill],
                                              np.nextafter(lo, -math.inf), hi))  # fmt: skip

    def control(self, row: np.ndarray | np.void) -> None:
        """One controller event (CONTROL_DTYPE record): the hi-hat pedal and chokes."""
        self._controls.append(np.array(row, dtype=CONTROL_DTYPE))

    def _apply(self, decisions: list[Decision]) -> None:
        for d in decisions:
            k = d.index - self._first
            if k < 0:
                continue
            note = self._notes[k]
            note.limb, note.piece, note.decided = d.limb, d.piece, True
            note.hand = d.limb in (0, 1) and d.piece >= 0
            if note.hand:
                r = note.row
                self.predictor.observe(float(r["time_s"]), d.limb, d.piece, int(r["zone"]),
                                       int(r["velocity"]))  # fmt: skip

    def next_due_s(self, after_s: float) -> float | None:
        """The first clock time after ``after_s`` at which an undecided note gets committed
        (a service polls :meth:`poses_until` then, not only on its tick), or None."""
        for n in self._notes:
            due = float(n.row["time_s"]) + self.params.lookahead_s
            if not n.decided and due > after_s:
                return due
        return None

    # -- output --------------------------------------------------------------------------------

    def poses_until(self, now_s: float) -> PoseBatch:
        """Commit what ``now_s`` allows and return the samples to publish: show times up to
        ``now_s + D`` (provisional) or ``now_s + D - L``. A provisional batch may start before
        the end of the previous one: it replaces the samples it covers (see the module
        docstring)."""
        p = self.params
        self._apply(self.sticker.advance(now_s))
        final = now_s - p.lookahead_s  # every note up to here is decided
        top = now_s if p.provisional else final
        if self._horizon is None:
            self._horizon = top - 1.0 / p.rate_hz
        start = self._horizon
        if p.predict:
            self._update_guesses(final, now_s)
        # what was published past the last committed horizon is provisional: a change of the
        # notes re-sends it from there (with D = L its first tick may already be on screen)
        rewind = min(start, max(self._final, final - p.delay_s)) if p.provisional else start
        refreshed = (top > start or p.provisional) and self._refresh(rewind, final)
        if refreshed:
            start = rewind
            if self.pause is not None:
                self.pause()
        self._final = max(self._final, final)
        if top <= start:
            if refreshed:
                self._cache_t, self._cache_rows = np.zeros(0), np.zeros(0, self.dtype)
            return PoseBatch(np.zeros(0), np.zeros(0, self.dtype))
        # the samples held ahead are replaced only once the new ones are ready: a quick
        # contact answered in a pause meanwhile fills its batch from the old ones
        if refreshed:
            self._cache_t, self._cache_rows = self._sample_ahead(start, top + p.chunk_s)
        elif self._cache_t.size == 0 or self._cache_t[-1] < top:
            more_t, more = self._sample_ahead(max(start, self._cache_end(start)), top + p.chunk_s)
            self._cache_t = np.concatenate([self._cache_t, more_t])
            self._cache_rows = np.concatenate([self._cache_rows, more])
        take = (self._cache_t > start) & (self._cache_t <= top)
        times, rows = self._cache_t[take], self._cache_rows[take]
        later = self._cache_t > top
        self._cache_t, self._cache_rows = self._cache_t[later], self._cache_rows[later]
        self._horizon = max(top, start)
        self._remember(times, rows, final)
        return self._batch(*self._with_struck(times, rows, start, top))

    def _batch(self, times: np.ndarray, rows: np.ndarray) -> PoseBatch:
        """Samples at performance ``times`` as a batch on show time (see :class:`PoseBatch`)."""
        if times.size == 0:
            return PoseBatch(np.zeros(0), np.zeros(0, self.dtype))
        rows = rows.copy()
        rows["time_s"] = (times - float(times[0])).astype(np.float32)
        return PoseBatch(times + self.params.delay_s, rows)

    def _held(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples published lately and held ahead, by time (after a re-animation the
        held ones may start before the end of the published ones)."""
        t = np.concatenate([self._sent_t, self._cache_t])
        order = np.argsort(t, kind="stable")
        return t[order], np.concatenate([self._sent_rows, self._cache_rows])[order]

    def _remember(self, times: np.ndarray, rows: np.ndarray, final: float) -> None:
        """Keep what was published for a quarter second (the body quick contacts start from;
        a re-sent range replaces what was sent there); forget quick contacts the curves
        now have."""
        if times.size:
            older = self._sent_t < times[0]
            t_all = np.concatenate([self._sent_t[older], times])
            recent = t_all > t_all[-1] - SENT_KEEP_S
            self._sent_t = t_all[recent]
            self._sent_rows = np.concatenate([self._sent_rows[older], rows])[recent]
        contacts = self._curves.contacts_s if self._curves is not None else np.zeros(0)
        self._struck = {
            t: r for t, r in self._struck.items()
            if t > final - SENT_KEEP_S and not np.any(contacts == t)
        }  # fmt: skip

    def _with_struck(self, times: np.ndarray, rows: np.ndarray, start: float, top: float
                     ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """A batch from curves that lack a hit still carries that hit's quick contact (it
        arrived while they were being built): the display's track would lose it otherwise."""
        add = [t for t in self._struck if start < t <= top]
        if not add:
            return times, rows
        keep = ~np.isin(times, add)
        t_all = np.concatenate([times[keep], np.array(add)])
        r_all = np.concatenate([rows[keep], np.array([self._struck[t] for t in add], self.dtype)])
        order = np.argsort(t_all, kind="stable")
        return t_all[order], r_all[order]

    def _cache_end(self, start: float) -> float:
        return float(self._cache_t[-1]) if self._cache_t.size else start

    def _sample_ahead(self, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
        """Samples of the current curves in ``(lo, hi]``, on the rate grid plus every committed
        contact: one call per chunk costs about what one sample does."""
        curves = self._curves
        assert curves is not None
        step = 1.0 / self.params.rate_hz
        grid = np.arange(math.floor(lo / step) + 1, math.floor(hi / step) + 1) * step
        c = curves.contacts_s
        times = np.unique(np.concatenate([grid[grid > lo], c[(c > lo) & (c <= hi)]]))
        if times.size == 0:
            return times, np.zeros(0, self.dtype)
        return times, self._sample(times)

    def _sample(self, times: np.ndarray) -> np.ndarray:
        assert self._curves is not None
        rows, faded = sample_curves(self._curves, self._old, self._fade, times, self.pause)
        if faded:
            self._old = None
        return rows

    # -- the window ----------------------------------------------------------------------------

    def _update_guesses(self, horizon: float, now_s: float) -> None:
        p = self.params
        pending = [n for n in self._notes if not n.decided]
        for limb in (0, 1):
            g = self._guesses.get(limb)
            if g is not None:
                near = [
                    n for n in pending if abs(float(n.row["time_s"]) - g.time_s) <= g.period_s / 3
                ]
                done = any(
                    n.decided and n.limb == limb and abs(float(n.row["time_s"]) - g.time_s)
                    <= g.period_s / 3 and float(n.row["time_s"]) <= horizon
                    for n in self._notes[-8:]
                )  # fmt: skip
                if done:
                    g = None
                elif near:
                    # it came: it will be committed before the horizon gets there, unless it
                    # came later than the guess, which then moves to it
                    t = float(near[0].row["time_s"])
                    if t > g.time_s - p.guard_s and t != g.time_s:
                        g = Guess(t, limb, g.piece, g.zone, g.velocity, g.period_s)
                elif horizon >= g.time_s - p.guard_s:
                    g = None  # it did not come: settle back
            if g is None:
                last = max((float(n.row["time_s"]) for n in self._notes
                            if n.decided and n.limb == limb), default=-math.inf)  # fmt: skip
                g = self.predictor.guess(limb, max(horizon + p.guard_s, last + 1e-3, now_s))
                if g is not None and g.time_s - horizon > 2.5:
                    g = None
            if g is None:
                self._guesses.pop(limb, None)
            else:
                self._guesses[limb] = g

    def _refresh(self, start: float, horizon: float) -> bool:
        """Rebuild the curves if the window's notes changed; True when they were rebuilt."""
        p = self.params
        # old notes leave the window half a window at a time: each departure alone would
        # otherwise cost a re-animation per note
        if self._notes and float(self._notes[0].row["time_s"]) < horizon - 1.5 * p.window_s:
            while (
                self._notes
                and float(self._notes[0].row["time_s"]) < horizon - p.window_s
                and (self._notes[0].decided)
            ):
                self._notes.pop(0)
                self._first += 1
            self._controls = [
                c for c in self._controls if float(c["time_s"]) >= horizon - p.window_s
            ]
        keep: list[tuple[np.ndarray, int, int]] = []
        # arrived notes can be shown before their decision
        ahead = p.provisional or p.delay_s > p.lookahead_s
        for n in self._notes:
            if n.decided:
                # feet are decided on arrival; with D = L they join with their hands' chord,
                # which saves re-running the body for nothing the horizon can show yet
                if n.limb >= 0 and n.piece >= 0 and (ahead or float(n.row["time_s"]) <= horizon):
                    keep.append((n.row, n.limb, n.piece))
            elif ahead:
                limb, piece = self._provisional_limb(n)
                if limb >= 0:
                    keep.append((n.row, limb, piece))
        guesses = sorted(self._guesses.values(), key=lambda g: g.time_s)
        epoch = math.floor(horizon / p.epoch_s)
        key = (
            tuple((float(r["time_s"]), li, pi) for r, li, pi in keep),
            tuple((g.time_s, g.limb, g.piece) for g in guesses),
            epoch,
            len(self._controls),
        )
        if self._curves is not None and self._curves.key[:3] == key[:3]:
            # only the pedal moved: its openness joins at most every ``control_every_s``
            # (each hi-hat CC4 step would otherwise cost a whole re-animation)
            if key[3] == self._curves.key[3] or horizon - self._refreshed_at < p.control_every_s:
                return False
        self._refreshed_at = horizon
        rows = [r for r, _, _ in keep]
        limbs = [li for _, li, _ in keep]
        pieces = [pi for _, _, pi in keep]
        for g in guesses:
            rec = np.zeros((), ONSET_DTYPE)
            rec["time_s"], rec["velocity"], rec["zone"] = g.time_s, g.velocity, g.zone
            rec["instrument"] = _instrument_of(self.rig, g.piece)
            rec["openness"] = np.nan
            rows.append(rec)
            limbs.append(g.limb)
            pieces.append(g.piece)
        onsets = np.array(rows, dtype=ONSET_DTYPE).reshape(-1)
        order = np.argsort(onsets["time_s"], kind="stable")
        onsets = onsets[order]
        limb_a = np.array(limbs, np.int8).reshape(-1)[order]
        piece_a = np.array(pieces, np.int16).reshape(-1)[order]
        st = Sticking(onsets, limb_a, piece_a, {}, "online", self.rig.kit.name)
        controls = (
            np.array(self._controls, CONTROL_DTYPE).reshape(-1)
            if self._controls
            else np.zeros(0, CONTROL_DTYPE)
        )
        openness = hihat_openness(onsets, controls, cc_open=self.cc_open)
        anim = animate(self.rig, st, self._beats(horizon, keep), openness, strokes=self.strokes,
                       pause=self.pause, memo=self._clearance)  # fmt: skip
        self.animations += 1
        committed = np.array(sorted(float(r["time_s"]) for r, _, _ in keep))
        new = Curves(anim, st, key, committed)
        if self._curves is not None:
            self._old = self._curves
            nxt = committed[committed > start]
            length = p.blend_s if nxt.size == 0 else min(p.blend_s, float(nxt[0]) - start)
            self._fade = (start, max(length, 0.0))
        self._curves = new
        return True

    def _provisional_limb(self, note: _Note) -> tuple[int, int]:
        """A pending note's likely limb and piece: what the online sticking's cheapest path
        so far gives it (99.5 % the same as its decision L later, on 12 GMD grooves; the
        old rule, a predictor guess near it or the hand that last played its piece, 87 %)."""
        return self.sticker.provisional(note.index)

    def _beats(self, horizon: float, keep: list[tuple[np.ndarray, int, int]]) -> np.ndarray:
        """Beat times for the torso's sway: the hands' pulse while playing, breathing when idle."""
        times = np.array([float(r["time_s"]) for r, li, _ in keep if li in (0, 1)])
        period = self.params.idle_period_s
        anchor = math.floor(horizon / self.params.epoch_s) * self.params.epoch_s
        if times.size >= 4 and horizon - times[-1] < 1.0:
            ioi = np.diff(times)
            ioi = ioi[ioi > 0.05]
            if ioi.size:
                period = float(np.median(ioi))
                while period < 0.35:
                    period *= 2.0
                anchor = float(times[-1])
        lo = horizon - self.params.window_s - 1.0
        hi = horizon + 2 * self.params.epoch_s
        k0 = math.floor((lo - anchor) / period)
        k1 = math.ceil((hi - anchor) / period)
        return anchor + period * np.arange(k0, k1 + 1)


def _instrument_of(rig: Rig, piece: int) -> int:
    plays = rig.kit.pieces[piece].plays
    return INSTRUMENTS.index(plays[0]) if plays else 0
