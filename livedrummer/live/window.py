"""The live synth's note window: which notes the body is animated from, with which limbs.

Why this shape. The live synth re-animates a sliding window of recent notes (see
:mod:`livedrummer.live.synth`); what goes into that window is a job of its own, with its own
state: the notes that arrived (each with its stream index, its decided limb once the online
sticking (:class:`~livedrummer.sticking.online.OnlineSticker`) commits it, or its
provisional one before), the predictor's guesses (:class:`~livedrummer.live.predict.HandPredictor`:
at most one per hand, at its expected next onset, so the upswing starts on time), and the
controller events (hi-hat pedal, cymbal chokes) of the same stretch of time. This module
keeps them and turns them into what the curves are built from (:meth:`NoteWindow.content`):
one time-ordered :class:`~livedrummer.sticking.result.Sticking` of notes and guesses, the
committed contacts, the torso's beats (the music's, from an online
:class:`~livedrummer.live.beat.BeatTracker` fed every onset, once it has a tempo; before, the
hands' pulse), the window's controls and chokes, and a key that
changes exactly when the curves would.

Guesses. When the committed horizon gets within ``guard_s`` of a guess and no onset has
arrived near it, it is dropped (the body settles back); when an onset has arrived (its limb
still pending), the guess moves to that exact time and is replaced by the committed note
when the horizon reaches it.

Limits: notes and controls leave the window half a window at a time, once they are
``window_s`` behind the committed horizon (a departure alone would otherwise cost a
re-animation per note), so it holds at most 1.5 ``window_s`` of notes: its size follows the
playing rate, never the length of the show. A flood (hundreds of notes a second) would make
every re-animation cost in proportion, so past ``max_notes`` the oldest decided notes leave
at once, down to half of it, as long as they lie more than ``keep_s`` (D, the furthest a
re-send reaches back) behind the committed horizon: at flood rates the curves then cover
less than ``window_s``, and a stroke's approach may change behind what is re-sent. A
cymbal whose hit has left the window stops swinging (its wobble, ``eta`` 0.08 per second, is
then under a tenth of its start). Chokes are resolved to pieces through the note map given
(none: chokes are ignored).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from livedrummer.body.rig import Rig
from livedrummer.body.sample import kit_choke_times
from livedrummer.kit.vocabulary import INSTRUMENTS
from livedrummer.live.beat import BeatTracker, downbeat_weights, onset_weights
from livedrummer.live.predict import Guess, HandPredictor
from livedrummer.midi.notemap import NoteMap
from livedrummer.sticking.online import Decision, OnlineSticker
from livedrummer.sticking.result import MERGED, NOT_PLAYED, Sticking
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind


@dataclass(frozen=True)
class WindowParams:
    """The window's share of :class:`~livedrummer.live.synth.SynthParams`."""

    lookahead_s: float
    ahead: bool  # arrived notes join before their decision (provisional poses, or D > L)
    window_s: float
    guard_s: float
    idle_period_s: float
    epoch_s: float
    max_notes: int  # at most this many notes (flood guard: see the module docstring)
    keep_s: float  # notes this close behind the committed horizon never leave early (D)


@dataclass
class Note:
    row: np.ndarray  # one ONSET_DTYPE record (0-d array)
    index: int  # its position in the stream (the sticking's index)
    limb: int = NOT_PLAYED
    piece: int = -1
    decided: bool = False
    hand: bool = False

    @property
    def time_s(self) -> float:
        return float(self.row["time_s"])


@dataclass(frozen=True)
class WindowContent:
    """What the curves are built from (see :meth:`NoteWindow.content`)."""

    sticking: Sticking  # notes and guesses, by time
    contacts_s: np.ndarray  # the notes' times (no guesses), sorted
    beats_s: np.ndarray  # the torso's beat times
    controls: np.ndarray  # CONTROL_DTYPE, the window's
    chokes: list[np.ndarray] | None  # per piece, choke times (None without a note map)
    #: (notes, guesses, torso epoch, chokes, pedal events): the curves are rebuilt when the
    #: first four change, and at most every ``control_every_s`` when only the last does
    key: tuple[object, ...]


class NoteWindow:
    """Pending and recent notes, their limbs and guesses, the online sticker (see the module
    docstring)."""

    def __init__(self, rig: Rig, params: WindowParams, note_map: NoteMap | None = None) -> None:
        self.rig = rig
        self.params = params
        self.note_map = note_map
        self.sticker = OnlineSticker(rig.kit, params.lookahead_s, keep_onsets=False)
        self.predictor = HandPredictor()
        self._beat = BeatTracker()  # the music's beat, for the torso (see _beats)
        self.reset()

    def reset(self) -> None:
        self.sticker.reset()
        self.predictor.reset()
        self._beat.reset()
        self._beat_todo: list[tuple[float, float, float]] = []  # heard, not yet tracked
        self._notes: list[Note] = []  # every note since the window start, by stream index
        self._first = 0  # stream index of self._notes[0]
        self._controls: list[np.ndarray] = []
        self._guesses: dict[int, Guess] = {}
        self.merged = 0  # notes decided as merged into another stroke (a flam of its hand)

    # -- input ---------------------------------------------------------------------------------

    def add(self, recs: np.ndarray) -> list[Note]:
        """Onsets (ONSET_DTYPE array, arrival order) join; returns their notes."""
        notes = []
        weights, downbeats = onset_weights(recs), downbeat_weights(recs)
        for i, rec in enumerate(recs):
            note = Note(np.array(rec, dtype=ONSET_DTYPE), self._first + len(self._notes))
            self._notes.append(note)
            notes.append(note)
            self._apply(self.sticker.process(rec))
            self._beat_todo.append((float(rec["time_s"]), float(weights[i]), float(downbeats[i])))
        if recs.size:  # also while no poses are asked for (a re-animation answering a flood)
            self.prune(float(recs["time_s"].max()) - self.params.lookahead_s)
        return notes

    @property
    def beat(self) -> BeatTracker:
        """The beat tracker, fed every onset heard so far. Onsets join it here, when it is
        read (on the synth's tick), not on arrival: its tempo search costs up to several
        milliseconds now and then, which a hit's answer must not wait for; fed in order, it
        gives what it would have given on arrival."""
        self.track_heard(self.take_heard())
        return self._beat

    def take_heard(self) -> list[tuple[float, float, float]]:
        """The onsets heard since the last call that the beat tracker has not had yet (time,
        weight, downbeat evidence), for :meth:`track_heard`."""
        todo, self._beat_todo = self._beat_todo, []
        return todo

    def track_heard(self, heard: list[tuple[float, float, float]]) -> None:
        """Feed the beat tracker what :meth:`take_heard` gave. Only the beat tracker is
        touched: a service whose other thread adds notes meanwhile (under its lock) may call
        this without the lock, from the one thread that reads :attr:`beat`."""
        for time_s, weight, downbeat in heard:
            self._beat.process(time_s, weight, downbeat)

    def control(self, row: np.ndarray | np.void) -> None:
        rec = np.array(row, dtype=CONTROL_DTYPE)
        self._controls.append(rec)
        self._prune_controls(float(rec["time_s"]) - self.params.lookahead_s)

    def advance(self, now_s: float) -> None:
        """Commit what the sticking decides by clock time ``now_s``."""
        self._apply(self.sticker.advance(now_s))

    def _apply(self, decisions: list[Decision]) -> None:
        for d in decisions:
            if d.reason is not None and d.reason.startswith(MERGED):
                self.merged += 1
            k = d.index - self._first
            if k < 0:
                continue
            note = self._notes[k]
            note.limb, note.piece, note.decided = d.limb, d.piece, True
            note.hand = d.limb in (0, 1) and d.piece >= 0
            if note.hand:
                r = note.row
                self.predictor.observe(
                    float(r["time_s"]), d.limb, d.piece, int(r["zone"]), int(r["velocity"])
                )

    def limbs(self, notes: list[Note]) -> tuple[np.ndarray, np.ndarray]:
        """Limb and piece of each note: its decision, else its provisional limb."""
        played = [(n.limb, n.piece) if n.decided else self.provisional(n) for n in notes]
        return (
            np.array([li for li, _ in played], dtype=np.int64),
            np.array([pi for _, pi in played], dtype=np.int64),
        )

    def provisional(self, note: Note) -> tuple[int, int]:
        """A pending note's likely limb and piece: what the online sticking's cheapest path
        so far gives it (99.5 % the same as its decision L later, on 12 GMD grooves; the
        old rule, a predictor guess near it or the hand that last played its piece, 87 %)."""
        return self.sticker.provisional(note.index)

    def next_due_s(self, after_s: float) -> float | None:
        """The first clock time after ``after_s`` at which an undecided note gets committed."""
        for n in self._notes:
            due = n.time_s + self.params.lookahead_s
            if not n.decided and due > after_s:
                return due
        return None

    # -- guesses -------------------------------------------------------------------------------

    def update_guesses(self, horizon: float, now_s: float) -> None:
        """Each hand's guess kept, moved, dropped or made anew (see the module docstring)."""
        p = self.params
        pending = [n for n in self._notes if not n.decided]
        for limb in (0, 1):
            g = self._guesses.get(limb)
            if g is not None:
                near = [n for n in pending if abs(n.time_s - g.time_s) <= g.period_s / 3]
                done = any(
                    n.decided
                    and n.limb == limb
                    and abs(n.time_s - g.time_s) <= g.period_s / 3
                    and n.time_s <= horizon
                    for n in self._notes[-8:]
                )
                if done:
                    g = None
                elif near:
                    # it came: it will be committed before the horizon gets there, unless it
                    # came later than the guess, which then moves to it
                    t = near[0].time_s
                    if t > g.time_s - p.guard_s and t != g.time_s:
                        g = Guess(t, limb, g.piece, g.zone, g.velocity, g.period_s)
                elif horizon >= g.time_s - p.guard_s:
                    g = None  # it did not come: settle back
            if g is None:
                last = max(
                    (n.time_s for n in self._notes if n.decided and n.limb == limb),
                    default=-math.inf,
                )
                g = self.predictor.guess(limb, max(horizon + p.guard_s, last + 1e-3, now_s))
                if g is not None and g.time_s - horizon > 2.5:
                    g = None
            if g is None:
                self._guesses.pop(limb, None)
            else:
                self._guesses[limb] = g

    # -- what the curves are built from --------------------------------------------------------

    def prune(self, horizon: float) -> None:
        """Notes and controls ``window_s`` behind the committed ``horizon`` leave, half a
        window at a time; past ``max_notes``, the oldest notes (undecided notes stay). Also
        done as notes and controls arrive, with their own time less ``L`` as the horizon."""
        p = self.params
        w = p.window_s
        notes = self._notes
        if notes and notes[0].time_s < horizon - 1.5 * w:
            k = 0
            while k < len(notes) and notes[k].time_s < horizon - w and notes[k].decided:
                k += 1
            del notes[:k]
            self._first += k
        if len(notes) > p.max_notes:
            k, over = 0, len(notes) - p.max_notes // 2
            while k < over and notes[k].decided and notes[k].time_s < horizon - p.keep_s:
                k += 1
            del notes[:k]
            self._first += k
        self._prune_controls(horizon)

    def _prune_controls(self, horizon: float) -> None:
        w = self.params.window_s
        ctl = self._controls
        if ctl and float(ctl[0]["time_s"]) < horizon - 1.5 * w:
            self._controls = [c for c in ctl if float(c["time_s"]) >= horizon - w]

    def content(self, horizon: float) -> WindowContent:
        """The window's notes (decided ones, and with ``ahead`` arrived ones with their
        provisional limbs) and guesses, as of the committed ``horizon``."""
        p = self.params
        keep: list[tuple[np.ndarray, int, int]] = []
        for n in self._notes:
            if n.decided:
                # feet are decided on arrival; with D = L they join with their hands' chord,
                # which saves re-running the body for nothing the horizon can show yet
                if n.limb >= 0 and n.piece >= 0 and (p.ahead or n.time_s <= horizon):
                    keep.append((n.row, n.limb, n.piece))
            elif p.ahead:
                limb, piece = self.provisional(n)
                if limb >= 0:
                    keep.append((n.row, limb, piece))
        guesses = sorted(self._guesses.values(), key=lambda g: g.time_s)
        controls = (
            np.array(self._controls, CONTROL_DTYPE).reshape(-1)
            if self._controls
            else np.zeros(0, CONTROL_DTYPE)
        )
        chokes = (
            kit_choke_times(controls, self.note_map, self.rig.kit)
            if self.note_map is not None
            else None
        )
        is_choke = controls["kind"] == ControlKind.CHOKE
        key = (
            tuple((float(r["time_s"]), li, pi) for r, li, pi in keep),
            tuple((g.time_s, g.limb, g.piece) for g in guesses),
            math.floor(horizon / p.epoch_s),
            tuple(tuple(c.tolist()) for c in chokes) if chokes is not None else (),
            int(np.sum(~is_choke)),
        )
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
        sticking = Sticking(
            onsets[order],
            np.array(limbs, np.int8).reshape(-1)[order],
            np.array(pieces, np.int16).reshape(-1)[order],
            {},
            "online",
            self.rig.kit.name,
        )
        contacts = np.array(sorted(float(r["time_s"]) for r, _, _ in keep))
        beats = self._beats(horizon, keep)
        return WindowContent(sticking, contacts, beats, controls, chokes, key)

    def _beats(self, horizon: float, keep: list[tuple[np.ndarray, int, int]]) -> np.ndarray:
        """Beat times for the torso's sway and the head's bob: the beat tracker's
        (:mod:`livedrummer.live.beat`) while playing, else the hands' pulse, breathing when
        idle."""
        p = self.params
        lo, hi = horizon - p.window_s - 1.0, horizon + 2 * p.epoch_s
        last = float(keep[-1][0]["time_s"]) if keep else -math.inf
        if self.beat.period_s is not None and horizon - last < 1.0:
            return self.beat.beats(lo, hi)
        times = np.array([float(r["time_s"]) for r, li, _ in keep if li in (0, 1)])
        period = p.idle_period_s
        anchor = math.floor(horizon / p.epoch_s) * p.epoch_s
        if times.size >= 4 and horizon - times[-1] < 1.0:
            ioi = np.diff(times)
            ioi = ioi[ioi > 0.05]
            if ioi.size:
                period = float(np.median(ioi))
                while period < 0.35:
                    period *= 2.0
                anchor = float(times[-1])
        lo = horizon - p.window_s - 1.0
        hi = horizon + 2 * p.epoch_s
        k0 = math.floor((lo - anchor) / period)
        k1 = math.ceil((hi - anchor) / period)
        return anchor + period * np.arange(k0, k1 + 1)


def _instrument_of(rig: Rig, piece: int) -> int:
    plays = rig.kit.pieces[piece].plays
    return INSTRUMENTS.index(plays[0]) if plays else 0
