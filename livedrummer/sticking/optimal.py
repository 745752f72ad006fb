"""The default strategy: the minimum-cost sticking over the whole piece, by dynamic programming.

Kragtwijk et al. proposed a shortest-path search over all stickings and stopped at the size of
the search space. The space is small once it is seen the right way: after each step (one hand
note, or a two-note chord) one hand is on the piece just struck, so a state is only *which hand
struck* and *where the other hand is*: 2 x P states for a kit of P pieces. Each step's costs
(:mod:`.cost`) depend on the previous state and, for the speed terms, on when each hand last
struck; that time is carried along each state's surviving path, which keeps the programme small
(the usual approximation of a Viterbi search with path-dependent costs; it is exact for every
term but the idle hand's last stroke time).

:class:`Trellis` is the forward recursion, shared with the online form (:mod:`.online`), which
commits decisions a fixed lag behind; :func:`optimal` runs it over a whole piece and backtracks
once. Per step it costs a few dozen numpy operations on 4 x P values, so a whole piece goes
at tens of thousands of notes per second, whatever its length.

Triplet runs (:mod:`.cost`) need one fact more than a state: whether the previous step was a
single drum note on the sixteenth-triplet grid, a sixth of a beat before this one. That is the
same for every state (it is the input's, not the sticking's), so the trellis keeps it beside
the step's time, and a state's hand tells whether the run's hands alternated. A hand passing
the other onto a neighbouring drum is charged the full crossing when it strikes, and the
difference to the pass's price is given back, along that state's path, only when the next note
of the run is the other hand on the same drum: a pass is cheap where the hands then meet there
(a drummer's move around the toms), never where the run ends crossed. So the online form, which
commits a note before the next is heard, does not pass; its short lookahead plays the change
of drum without the pass (a double or a lead change), as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking.cost import CostModel, Weights
from livedrummer.sticking.prepare import (
    TRIPLET_TOL,
    UNANNOTATED,
    Routed,
    apply_explicit,
    apply_merged,
    beat_features,
    chords,
    reduce_chord,
    route,
)
from livedrummer.sticking.result import LIMB_CODE, Sticking

INF = np.inf
_HAND_CODE = (LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH])


@dataclass(frozen=True)
class Snapshot:
    value: np.ndarray
    main: int
    time_s: float
    times: np.ndarray
    doubles: np.ndarray
    steps: int
    sixth_s: float
    refund: np.ndarray


class Trellis:
    """Forward recursion of the sticking programme (see the module docstring).

    The state vector has 2P entries: ``(h, q)`` at ``h * P + q`` means hand ``h`` (0 right,
    1 left) struck the step's first note and the other hand is at piece ``q``. After a chord
    both hands struck: ``(0, b)`` is right hand on the first note, left on ``b``. ``times``
    holds, per state, the right hand's last stroke time (first 2P) and the left's (last 2P),
    along that state's surviving path. Per-(piece, previous piece) lookups are cached, so a
    step is a dozen array operations on 4P values.
    """

    def __init__(self, model: CostModel) -> None:
        self.model = model
        self.backpointers: list[np.ndarray] = []
        n = model.pieces
        self._ar2 = np.arange(2 * n)
        self._swap = np.concatenate((np.arange(2 * n, 4 * n), np.arange(2 * n)))
        ar = np.arange(n)
        self._at = [
            np.concatenate((np.full(n, main), ar, ar, np.full(n, main))) for main in range(n)
        ]  # for every state: the right hand's piece (first 2P), the left hand's (last 2P)
        self._tables: dict[tuple[int, int, bool], tuple[np.ndarray, np.ndarray]] = {}
        self.reset()

    def reset(self) -> None:
        n = self.model.pieces
        self.value = np.full(2 * n, INF)
        home_r, home_l = self.model.home
        self.value[home_l] = 0.0  # right hand "struck" its home, left hand waits at its own
        self.main = home_r
        self.time_s = -10.0
        self.times = np.full(4 * n, -10.0)
        self.doubles = np.zeros(4 * n, dtype=bool)  # was that hand's last stroke a double?
        self.sixth_s = 0.0  # the last step's triplet sixth: a single drum note on that grid
        self.refund = np.zeros(2 * n)  # per state: a pass's crossing, returned if it is met
        self.backpointers = []
        self.offset = 0.0  # what normalisation took off the values: best total = offset + min

    def snapshot(self) -> Snapshot:
        return Snapshot(
            self.value.copy(),
            self.main,
            self.time_s,
            self.times.copy(),
            self.doubles.copy(),
            len(self.backpointers),
            self.sixth_s,
            self.refund.copy(),
        )

    def restore(self, s: Snapshot) -> None:
        self.value, self.main, self.time_s = s.value.copy(), s.main, s.time_s
        self.times = s.times.copy()
        self.doubles = s.doubles.copy()
        self.sixth_s = s.sixth_s
        self.refund = s.refund.copy()
        del self.backpointers[s.steps :]

    def _table(self, p: int, run: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Stroke rows (4, 4P) and stance costs (4P) for striking ``p`` from every state
        (``run``: inside a triplet run, where neighbouring drums pass)."""
        key = (p, self.main, run)
        found = self._tables.get(key)
        if found is None:
            m = self.model
            n = m.pieces
            at = self._at[self.main]
            rp, lp = at[: 2 * n], at[2 * n :]
            st = m.pass_stance if run else m.stance
            found = (m.stroke[p][:, at], np.concatenate((st[p][lp], st[:, p][rp])))
            self._tables[key] = found
        return found

    def _hand(
        self, stroke: np.ndarray, at: np.ndarray, gap: np.ndarray, p: int, doubles: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Cost of hands moving from pieces ``at`` to ``p`` after ``gap`` seconds, and whether
        each stroke is a double (a second stroke after ``doubles`` counts as too fast)."""
        w = self.model.weights
        dist, lim, gmin, comfort = stroke
        cost = dist * (w.move_per_m + w.move_speed_s / np.maximum(gap, 0.03))
        fast = gap < lim
        double = ~fast & (gap < gmin) & (at == p)
        fast |= double & doubles
        cost += np.where(fast, w.too_fast * (2.0 - gap / gmin), 0.0)
        cost += w.double_stroke * double
        x = np.maximum(0.0, 1.0 - gap / comfort)
        cost += w.comfort * x * x
        return cost, double

    def step(
        self,
        p: int,
        t: float,
        beat: float,
        forced: int | None = None,
        sixth_s: float = 0.0,
        grouping: float = 0.0,
    ) -> None:
        """One hand note on piece ``p`` at ``t``; ``forced`` fixes the hand (0 right, 1 left);
        ``sixth_s`` and ``grouping``: the note on the sixteenth-triplet grid
        (:data:`~.prepare.BEAT_DTYPE`; 0 off it)."""
        m = self.model
        n = m.pieces
        n2 = 2 * n
        run = self._in_run(p, t, sixth_s)
        if run:
            beat = grouping
        stroke, stance = self._table(p)
        gap = t - self.times
        cost, double = self._hand(stroke, self._at[self.main], gap, p, self.doubles)
        near = gap[self._swap] <= m.stance_window_s
        cost += stance * near
        iso = min(1.0, (t - self.time_s) / m.weights.isolation_s)
        c0 = self.value + cost[:n2]
        c0 += m.bias[0, p] * iso + m.beat_bias[0, p] * beat
        c1 = self.value + cost[n2:]
        c1 += m.bias[1, p] * iso + m.beat_bias[1, p] * beat
        if run:  # hand to hand: a state whose hand struck the previous note strikes again
            c0[:n] += m.weights.triplet_double
            c1[n:] += m.weights.triplet_double
            if p == self.main:  # the other hand meets the passing one on its drum
                c0[n:] -= self.refund[n:]
                c1[:n] -= self.refund[:n]
        pm = self.main
        value = np.concatenate((c0[:n], c1[n:]))
        back = self._ar2.copy()
        k = int(np.argmin(c0[n:])) + n
        if c0[k] < value[pm]:
            value[pm], back[pm] = c0[k], k
        k = int(np.argmin(c1[:n]))
        if c1[k] < value[n + pm]:
            value[n + pm], back[n + pm] = c1[k], k
        if forced is not None:
            value[(1 - forced) * n : (2 - forced) * n] = INF
        times = np.empty_like(self.times)
        times[:n] = t
        times[n:n2] = self.times[back[n:]]
        times[n2 : n2 + n] = self.times[n2 + back[:n]]
        times[n2 + n :] = t
        doubles = np.empty_like(self.doubles)
        doubles[:n] = double[back[:n]]
        doubles[n:n2] = self.doubles[back[n:]]
        doubles[n2 : n2 + n] = self.doubles[n2 + back[:n]]
        doubles[n2 + n :] = double[n2 + back[n:]]
        refund = np.zeros(n2)
        if run:
            owed = (stance - self._table(p, True)[1]) * near
            refund[:n] = owed[:n2][back[:n]]
            refund[n:] = owed[n2:][back[n:]]
        self._advance(value, back, times, doubles, p, t)
        self.sixth_s = sixth_s if m.drum[p] else 0.0
        self.refund = refund

    def _in_run(self, p: int, t: float, sixth_s: float) -> bool:
        """Is a drum note at ``t`` the next of a sixteenth-triplet run (see the docstring)?"""
        if sixth_s <= 0.0 or self.sixth_s <= 0.0 or not self.model.drum[p]:
            return False
        return abs(t - self.time_s - sixth_s) < TRIPLET_TOL * sixth_s

    def step_chord(self, a: int, b: int, t: float, forced: int | None = None) -> None:
        """Two hand notes at once; ``forced`` fixes the hand of the first (0 right, 1 left).

        The lead-hand-on-the-beat habit is left out: in a chord the lead hand can take only
        one of the notes, and which one is the pair's business (stance and preferred hands).
        """
        m = self.model
        n = m.pieces
        n2 = 2 * n
        at = self._at[self.main]
        gap = t - self.times
        value = np.full(n2, INF)
        back = np.zeros(n2, dtype=np.int64)
        doubles = np.zeros(4 * n, dtype=bool)
        iso = min(1.0, (t - self.time_s) / m.weights.isolation_s)
        for h, (r, left) in enumerate(((a, b), (b, a))):
            if forced is not None and forced != h:
                continue
            right_rows, left_rows = self._table(r)[0], self._table(left)[0]
            c, dr = self._hand(right_rows[:, :n2], at[:n2], gap[:n2], r, self.doubles[:n2])
            cl, dl = self._hand(left_rows[:, n2:], at[n2:], gap[n2:], left, self.doubles[n2:])
            c += self.value + cl
            extra = m.stance[r, left] + (m.bias[0, r] + m.bias[1, left]) * iso
            k = int(np.argmin(c))
            s = h * n + b
            value[s], back[s] = c[k] + extra, k
            doubles[s], doubles[n2 + s] = dr[k], dl[k]
        self._advance(value, back, np.full(4 * n, t), doubles, a, t)
        self.sixth_s = 0.0
        self.refund = np.zeros(n2)

    def _advance(
        self,
        value: np.ndarray,
        back: np.ndarray,
        times: np.ndarray,
        doubles: np.ndarray,
        main: int,
        t: float,
    ) -> None:
        best = float(value.min())
        if np.isfinite(best):
            value -= best
            self.offset += best
        self.value, self.times, self.doubles = value, times, doubles
        self.main, self.time_s = main, t
        self.backpointers.append(back)

    def best_path(self, start: int = 0) -> np.ndarray:
        """State of every step from ``start`` on, ending in the cheapest current state."""
        steps = len(self.backpointers)
        path = np.zeros(max(steps - start, 0), dtype=np.int64)
        s = int(np.argmin(self.value))
        for k in range(steps - 1, start - 1, -1):
            path[k - start] = s
            s = int(self.backpointers[k][s])
        return path


def plan_steps(routed: Routed, kit: Kit) -> tuple[list[tuple[int, ...]], dict[int, str]]:
    """Hand notes grouped into playable steps of one or two notes, with the reasons."""
    hand = np.flatnonzero(routed.hand)
    reasons: dict[int, str] = {}
    steps: list[tuple[int, ...]] = []
    for group in chords(routed.onsets["time_s"][hand]):
        keep, why = reduce_chord(hand[group].tolist(), routed, kit)
        reasons.update(why)
        steps.append(tuple(keep))
    return steps, reasons


def hand_of(state: int, pieces: int) -> int:
    return state // pieces


def apply_step(limb: np.ndarray, notes: tuple[int, ...], state: int, pieces: int) -> None:
    """Write the limbs a state gives a step's notes into ``limb``."""
    h = hand_of(state, pieces)
    limb[notes[0]] = _HAND_CODE[h]
    if len(notes) > 1:
        limb[notes[1]] = _HAND_CODE[1 - h]


def feed(
    trellis: Trellis,
    routed: Routed,
    notes: tuple[int, ...],
    beat: np.ndarray,
    forced: int | None = None,
) -> None:
    """Run one step of ``notes`` (indices into ``routed``; ``beat``: their
    :data:`~.prepare.BEAT_DTYPE` rows, by the same index) through the trellis."""
    t = float(routed.onsets["time_s"][notes[0]])
    if len(notes) == 1:
        b = beat[notes[0]]
        trellis.step(
            int(routed.piece[notes[0]]),
            t,
            float(b["strength"]),
            forced,
            float(b["sixth_s"]),
            float(b["grouping"]),
        )
    else:
        a, b = notes
        trellis.step_chord(int(routed.piece[a]), int(routed.piece[b]), t, forced)


def forced_hand(notes: tuple[int, ...], explicit: np.ndarray | None) -> int | None:
    """The hand (0 right, 1 left) a score fixes for a step's first note, if any."""
    if explicit is None:
        return None
    for k, i in enumerate(notes):
        if int(explicit[i]) in _HAND_CODE:
            h = _HAND_CODE.index(int(explicit[i]))
            return h if k == 0 else 1 - h
    return None


def optimal(
    onsets: np.ndarray,
    kit: Kit,
    *,
    beat_s: np.ndarray | None = None,
    weights: Weights | None = None,
    explicit: np.ndarray | None = None,
) -> Sticking:
    """Minimum-cost sticking of a whole piece (see the module docstring).

    ``explicit`` (int8 per onset, :data:`~.prepare.UNANNOTATED` where free) fixes limbs a
    score gives; the search then fits the free notes around them.
    """
    routed = route(onsets, kit)
    reasons = dict(routed.reasons)
    if explicit is not None:
        reasons.update(apply_explicit(routed, explicit, kit))
    steps, why = plan_steps(routed, kit)
    reasons.update(why)
    model = CostModel.from_kit(kit, weights)
    trellis = Trellis(model)
    beat = beat_features(routed.onsets["time_s"], beat_s)
    for notes in steps:
        feed(trellis, routed, notes, beat, forced_hand(notes, explicit))
    for notes, state in zip(steps, trellis.best_path().tolist(), strict=True):
        apply_step(routed.limb, notes, state, model.pieces)
    apply_merged(routed)
    if explicit is not None:  # a score that gives one instant's two notes to one hand wins too
        marked = (explicit != UNANNOTATED) & (routed.piece >= 0)
        routed.limb[marked] = explicit[marked]
    return Sticking(routed.onsets, routed.limb, routed.piece, reasons, "optimal", kit.name)
