"""The online stroke synthesizer: onsets in, one at a time; pose samples out, on show time.

Why this shape. The body's :func:`~livedrummer.body.animation.animate` builds a whole
performance's curves at once (about 20 ms whatever the length, for a few seconds of notes),
so the live synth does not re-implement strokes: it keeps a sliding window of notes and
re-runs the body over that window whenever the set of notes changes, then samples the curves
only for the times it has not published yet. :class:`LiveSynth` is the coordinator of three
parts, each with one job and its own state:

* the note window (:class:`~livedrummer.live.window.NoteWindow`): pending and recent notes,
  their decided or provisional limbs, the predictor's guesses, the controls, the online
  sticker;
* the curve set (:class:`~livedrummer.live.curves.CurveSet`): the current curves and the
  cross-fade from the old ones (slerp, so bones keep their length mid-fade); in this process,
  or in a worker process the synth service gives it (:mod:`services.synth.curveworker`);
* the sample ledger (:class:`~livedrummer.live.ledger.SampleLedger`): the one store of what
  was published, what is held ahead and the quick contacts.

Three timelines meet here:

* *performance time* is the onset's own time on the shared clock (its arrival stamp);
* the online sticking commits a hand note ``L`` (lookahead) after its onset, so at clock time
  ``now`` every note up to ``now - L`` is decided (the *committed horizon*);
* *show time* is performance time + ``D``: the display shows the pose sampled at ``t`` when
  the shared clock reads ``t + D``, and a contact sample is always included at exactly each
  onset + D.

Provisional poses (the default; ``SynthParams.provisional``). Waiting for the sticking's
decision would publish a hit's contact only ``L`` after the hit (``D - L`` before it is seen:
no slack at all with the default ``D = L``). Instead the synth samples up to ``now``: an
arrived, undecided note joins the window with its provisional hand (what the online
sticking's cheapest path so far gives it: its decision in 99.5 % of cases), so its stroke
goes out as soon as the window is re-animated. Everything published past the committed
horizon is provisional: when a decision, an arrival or a dropped guess changes the window,
the synth re-sends from the previous committed horizon (the display's
:class:`~livedrummer.live.track.PoseTrack` lets a batch replace the samples it covers),
cross-fading into the new curves before the next contact. With ``provisional=False`` samples
go out only up to ``now + D - L``, never twice.

Quick contacts. Re-animating the window takes about 10-20 ms; a hit does not wait for it.
:meth:`LiveSynth.process` solves every arriving hit's contact pose at once (the body as last
sampled near the onset, the striking limb put on its piece:
:func:`~livedrummer.live.quick.quick_contact`, a pure function of the read-only
:meth:`LiveSynth.quick_state`); :meth:`LiveSynth.take_quick` hands them out, with the
samples between them, and the service publishes them before re-animating.

Answering during a re-animation. :meth:`LiveSynth.poses_until` takes an ``answer`` callable,
called between the steps of a re-animation and of the sampling that follows (a few
milliseconds apart at most): the service passes the function that reads its socket, so a
hit that arrives meanwhile gets its contact out then, not after the re-animation. A service
with two threads passes ``lock`` instead (the synth service does:
:mod:`services.synth.service`): held by the caller, it is let go while the curves are
rebuilt and sampled, so the other thread answers hits then, not only between the steps. What
a re-animation reads was taken before it started, and the held samples are swapped only when
the new ones are complete; a batch built from curves that lack a hit answered meanwhile still
carries that hit's quick contact.

Chokes. With a note map, a cymbal choke (polyphonic aftertouch) in the window stops the
cymbal's wobble in the live poses as :func:`~livedrummer.body.sample.sample_poses` does
offline; a choke re-animates the window at once (it is rare) so the held samples after it
are replaced.

Style. The window is animated with the expression in force (a preset: SMED's gains, shares
and secondary motion); :meth:`LiveSynth.set_expression` changes it while playing, eased in
over ``style_ramp_s`` (:mod:`livedrummer.live.style`: the window is animated with both
expressions and the poses blended along the ramp, so no joint jumps).

Idle. With no notes the torso still sways on a slow "breathing" beat (the body's sway keyed on
``idle_period_s``), so the drummer never freezes.

Limits: re-animation costs 10-20 ms each time the window changes (about two times per note
of a groove: arrival, a new or dropped guess; old notes leave half a window at a time, and
a moving pedal alone re-animates at most every ``control_every_s``), so at 1,000 notes/s
most of the time goes to quick contacts and the strokes between them are re-animated only a
few times a second; a quick contact with a wrong provisional hand shows that hand striking
until the decision re-animates; hi-hat openness comes from the onsets and the pedal
controller of the window only. Memory is bounded by the window (notes, controls), the
ledger's quarter second of samples and the sticker's pending steps, whatever the length of
the show.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from livedrummer.body.animation import hihat_openness
from livedrummer.body.expression import Expression, with_param
from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import Rig
from livedrummer.body.strike import foot_contacts
from livedrummer.body.strokes import StrokeParams
from livedrummer.live.curves import Answer, CurveSet, CurveSource
from livedrummer.live.ledger import SampleLedger
from livedrummer.live.quick import QuickState, quick_contact
from livedrummer.live.settings import check_delay
from livedrummer.live.style import StyleRamp
from livedrummer.live.window import NoteWindow, WindowParams
from livedrummer.midi.notemap import NoteMap
from livedrummer.timeline.events import ONSET_DTYPE


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
    max_notes: int = 128  # the window's most notes (a flood's re-animations stay cheap)
    style_ramp_s: float = 0.5  # a change of expression is eased in over this long (style.py)

    def __post_init__(self) -> None:
        check_delay(self.lookahead_s, self.delay_s)  # the one check of 0 <= L <= D
        if not self.rate_hz > 0 or not self.window_s > 0:
            raise ValueError(f"rate {self.rate_hz} and window {self.window_s} must be > 0")
        if self.max_notes < 8:
            raise ValueError(f"max_notes {self.max_notes} must be >= 8")


class Lock(Protocol):
    """What ``poses_until(lock=...)`` needs of a lock (:class:`threading.Lock` has it)."""

    def acquire(self) -> bool: ...

    def release(self) -> None: ...


@contextmanager
def released(lock: Lock | None) -> Iterator[None]:
    """``lock`` (held by the caller) released for the block and taken back after it."""
    if lock is None:
        yield
        return
    lock.release()
    try:
        yield
    finally:
        lock.acquire()


@dataclass(frozen=True)
class PoseBatch:
    """Pose samples: ``show_s`` (float64 show times) and the matching pose records, whose
    ``time_s`` field holds the performance time relative to ``show_s[0] - D`` (float32 cannot
    hold clock times to the millisecond)."""

    show_s: np.ndarray
    rows: np.ndarray


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
        note_map: NoteMap | None = None,
        expression: Expression | None = None,
        curves: CurveSource | None = None,
    ) -> None:
        """``curves``: where the window is animated and sampled (default: a
        :class:`~livedrummer.live.curves.CurveSet` in this process, built with ``strokes``;
        one given was built with the same rig, ``blend_s`` and strokes)."""
        self.rig = rig
        self.params = p = params or SynthParams()
        self.cc_open = cc_open
        self.dtype = pose_dtype(len(rig.kit.pieces))
        ahead = p.provisional or p.delay_s > p.lookahead_s
        wp = WindowParams(
            p.lookahead_s,
            ahead,
            p.window_s,
            p.guard_s,
            p.idle_period_s,
            p.epoch_s,
            p.max_notes,
            p.delay_s,
        )
        self.window = NoteWindow(rig, wp, note_map)
        self.curves = curves if curves is not None else CurveSet(rig, p.blend_s, strokes)
        self.ledger = SampleLedger(self.dtype)
        self.style = StyleRamp(expression, p.style_ramp_s)
        self.feet = foot_contacts(rig)  # a quick contact's feet, solved once
        self.reset()

    def reset(self) -> None:
        self.window.reset()
        self.curves.reset()
        self.ledger.reset()
        self._committed = -math.inf  # the committed horizon (now - L) at the last call
        self.quick_contacts = 0  # hits whose contact went out before re-animating

    @property
    def animations(self) -> int:
        """How many times the body was re-run (for benchmarks)."""
        return self.curves.animations

    # -- input ---------------------------------------------------------------------------------

    def process(self, rows: np.ndarray | np.void, quick: bool = True) -> None:
        """Onsets (one ONSET_DTYPE record or an array of them, in arrival order; their times
        are the arrivals on the shared clock). ``quick``: also prepare their quick contacts
        (:meth:`take_quick`) with their decided or provisional limbs, all in one go (only with
        provisional poses: without, nothing goes out before the decision)."""
        recs = np.atleast_1d(np.asarray(rows, dtype=ONSET_DTYPE))
        notes = self.window.add(recs)
        if not (quick and self.params.provisional and notes):
            return
        limbs, pieces = self.window.limbs(notes)
        times, out = quick_contact(self.quick_state(), recs, limbs, pieces)
        if times.size:
            self.ledger.add_quick(times, out)
            self.quick_contacts += int(np.sum((limbs >= 0) & (pieces >= 0)))

    def control(self, row: np.ndarray | np.void) -> None:
        """One controller event (CONTROL_DTYPE record): the hi-hat pedal and chokes."""
        self.window.control(row)

    def set_expression(self, expression: Expression, now_s: float) -> None:
        """Play with ``expression`` from clock time ``now_s`` on, eased in (see
        :mod:`livedrummer.live.style`): the window is re-animated at each step of the ramp."""
        self.style.set(expression, now_s)

    def set_param(self, name: str, value: float, now_s: float) -> None:
        """One expression parameter (:data:`~livedrummer.body.expression.PARAMS`) set from
        clock time ``now_s`` on, eased in like a preset; ValueError names a bad name or value."""
        self.set_expression(with_param(self.style.target, name, value), now_s)

    def quick_state(self) -> QuickState:
        """A read-only copy for :func:`~livedrummer.live.quick.quick_contact`."""
        return QuickState(
            self.rig,
            self.dtype,
            self.curves.view(),
            *self.ledger.samples(),
            self.ledger.struck(),
            self.feet,
        )

    def take_quick(self) -> PoseBatch:
        """Quick contacts of the hits that arrived since the last call, to publish at once,
        ahead of :meth:`poses_until` (see :meth:`~livedrummer.live.ledger.SampleLedger.take_quick`).
        """
        return self._batch(*self.ledger.take_quick())

    def next_due_s(self, after_s: float) -> float | None:
        """The first clock time after ``after_s`` at which an undecided note gets committed
        (a service polls :meth:`poses_until` then, not only on its tick), or None."""
        return self.window.next_due_s(after_s)

    # -- output --------------------------------------------------------------------------------

    def poses_until(
        self, now_s: float, answer: Answer | None = None, *, lock: Lock | None = None
    ) -> PoseBatch:
        """Commit what ``now_s`` allows and return the samples to publish: show times up to
        ``now_s + D`` (provisional) or ``now_s + D - L``. A provisional batch may start before
        the end of the previous one: it replaces the samples it covers (see the module
        docstring). ``answer``, when given, is called between the steps of a re-animation
        and of the sampling (see the module docstring); it may call :meth:`process` and
        :meth:`take_quick`. ``lock``, when given, is held by the caller and released while
        the curves are rebuilt and sampled (the steps that take milliseconds), so that another
        thread holding it meanwhile may call :meth:`process` and :meth:`take_quick` (see the
        module docstring); ``answer`` is then called only while it is let go."""
        p = self.params
        self.window.advance(now_s)
        committed = now_s - p.lookahead_s  # every note up to here is decided
        top = now_s if p.provisional else committed
        ledger = self.ledger
        if ledger.published_s is None:
            ledger.published_s = top - 1.0 / p.rate_hz
        start = ledger.published_s
        if p.predict:
            self.window.update_guesses(committed, now_s)
        # what was published past the last committed horizon is provisional: a change of the
        # notes re-sends it from there (with D = L its first tick may already be on screen)
        rewind = min(start, max(self._committed, committed - p.delay_s)) if p.provisional else start
        refreshed = (top > start or p.provisional) and self._refresh(
            rewind, committed, answer, lock
        )
        if refreshed:
            start = rewind
            if answer is not None and lock is None:  # with a lock: only while it is let go
                answer()
        self._committed = max(self._committed, committed)
        if top <= start:
            if refreshed:
                ledger.drop_held()
            return self._batch(np.zeros(0), np.zeros(0, self.dtype))
        # the held samples are replaced only once the new ones are ready: a quick contact
        # answered meanwhile fills its batch from the old ones
        held = ledger.held_until()
        if refreshed:
            ledger.hold(*self._sample_ahead(start, top + p.chunk_s, answer, lock), replace=True)
        elif held is None or held < top:
            lo = max(start, held if held is not None else start)
            ledger.hold(*self._sample_ahead(lo, top + p.chunk_s, answer, lock), replace=False)
        curves = self.curves.current
        contacts = curves.contacts_s if curves is not None else np.zeros(0)
        return self._batch(*ledger.publish(start, top, committed, contacts))

    def _batch(self, times: np.ndarray, rows: np.ndarray) -> PoseBatch:
        """Samples at performance ``times`` as a batch on show time (see :class:`PoseBatch`)."""
        if times.size == 0:
            return PoseBatch(np.zeros(0), np.zeros(0, self.dtype))
        rows = rows.copy()
        rows["time_s"] = (times - float(times[0])).astype(np.float32)
        return PoseBatch(times + self.params.delay_s, rows)

    def _sample_ahead(
        self, lo: float, hi: float, answer: Answer | None, lock: Lock | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Samples of the current curves in ``(lo, hi]``, on the rate grid plus every committed
        contact: one call per chunk costs about what one sample does."""
        curves = self.curves.current
        if curves is None:
            raise RuntimeError("sampling before the first animation")
        step = 1.0 / self.params.rate_hz
        grid = np.arange(math.floor(lo / step) + 1, math.floor(hi / step) + 1) * step
        c = curves.contacts_s
        times = np.unique(np.concatenate([grid[grid > lo], c[(c > lo) & (c <= hi)]]))
        if times.size == 0:
            return times, np.zeros(0, self.dtype)
        with released(lock):
            return times, self.curves.sample(times, answer)

    def _refresh(
        self, start: float, horizon: float, answer: Answer | None, lock: Lock | None = None
    ) -> bool:
        """Rebuild the curves if the window's notes changed; True when they were rebuilt."""
        window = self.window
        window.prune(horizon)
        content = window.content(horizon)
        # a change of expression shapes what may still be (re-)sent: from ``start`` on
        change = self.style.change(start)
        key = (*content.key, self.style.target, change)
        current = self.curves.current
        if current is not None and current.key[:4] == key[:4] and current.key[5:] == key[5:]:
            # only the pedal moved: its openness joins at most every ``control_every_s``
            # (each hi-hat CC4 step would otherwise cost a whole re-animation)
            if (
                content.key[4] == current.key[4]
                or horizon - self.curves.built_at < self.params.control_every_s
            ):
                return False
        openness = hihat_openness(content.sticking.onsets, content.controls, cc_open=self.cc_open)
        expression = self.style.target
        with released(lock):  # what it reads was taken above; the quick path reads its view
            self.curves.rebuild(
                content.sticking,
                content.beats_s,
                openness,
                key,
                content.contacts_s,
                content.chokes,
                start,
                horizon,
                answer,
                expression,
                change,
            )
        return True
