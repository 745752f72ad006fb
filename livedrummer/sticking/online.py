"""The optimal strategy on a live stream: fixed-lag decisions, one onset at a time.

A live avatar cannot wait for the end of the song. :class:`OnlineSticker` runs the same forward
recursion as :func:`~.optimal.optimal` (:class:`~.optimal.Trellis`) as onsets arrive, and
commits a hand note once ``lookahead_s`` has passed since its onset: it takes the decision
from the cheapest path so far, then discards every path that disagrees, so later decisions stay
consistent with what was already shown. With a lookahead longer than the piece nothing is
committed before :meth:`flush`, and the result is the offline one exactly; with lookahead 0 each
note is decided on arrival from the past alone. Feet and notes the kit lacks need no lookahead
and are committed at once.

Time only advances with the stream: :meth:`process` treats the new onset's time as "now". A
live caller whose stream may pause should also call :meth:`advance` with its clock, so that no
decision waits longer than the lookahead. A hand note arriving within the chord window of an
already committed note joins its chord with the other hand (unless both would be on one hi-hat:
then the newcomer merges into the committed stroke, a double stroke of its hand); when both
hands are committed, a hi-hat goes to the pedal and anything else merges into the committed
stroke nearest to it (on its piece if one is: :func:`~.prepare.merge_into`), with the reason, so
no note is ever without a limb. A merged note of a pending step takes its partner's
provisional hand, and its decision when the step commits. Committed steps of the
recursion are dropped, so its state stays a few steps long however long the show. The onsets
themselves are kept (``onsets()``, a few dozen bytes each) unless ``keep_onsets=False``: then
the notes no pending step needs are dropped whenever the arrays fill (their reasons with
them), so a live show's sticker holds a few hundred notes at most, however long it runs.
Indices (``Decision.index``, :meth:`OnlineSticker.provisional`) count from the start of the
stream either way.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Limb, PieceKind, Zone
from livedrummer.sticking.cost import CostModel, Weights
from livedrummer.sticking.optimal import Snapshot, Trellis, apply_step, feed, hand_of
from livedrummer.sticking.prepare import (
    BEAT_DTYPE,
    CHORD_WINDOW_S,
    Routed,
    apply_merged,
    beat_features_at,
    foot_limb,
    kick_foot,
    merge_into,
    piece_table,
    reduce_chord,
    to_pedal,
)
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED, Sticking
from livedrummer.timeline.events import ONSET_DTYPE

_INITIAL = 256
_RH = LIMB_CODE[Limb.RH]
_PEDAL_ZONE = ZONES.index(Zone.PEDAL)
_PEDAL_HIHAT = HIHATS.index(HiHat.PEDAL)


@dataclass(frozen=True, slots=True)
class Decision:
    """The committed limb of one onset (``index``: its position in the stream, from 0)."""

    index: int
    limb: int  # LIMBS index or NOT_PLAYED
    piece: int  # kit.pieces index or -1
    reason: str | None
    pedal: bool  # the stroke was moved to the hi-hat pedal


@dataclass
class _Step:
    notes: list[int]  # every hand note of the chord that arrived, kept or not
    played: tuple[int, ...]
    time_s: float
    before: Snapshot
    committed: bool = False


class OnlineSticker:
    """Fixed-lag minimum-cost sticking (see the module docstring)."""

    def __init__(
        self,
        kit: Kit,
        lookahead_s: float,
        *,
        beat_s: np.ndarray | None = None,
        weights: Weights | None = None,
        keep_onsets: bool = True,
    ) -> None:
        if not lookahead_s >= 0.0:
            raise ValueError(f"lookahead_s must be >= 0, not {lookahead_s!r}")
        self.kit = kit
        self.lookahead_s = float(lookahead_s)
        self.beat_s = beat_s
        self.keep_onsets = keep_onsets
        self.model = CostModel.from_kit(kit, weights)
        self._table = piece_table(kit)
        self._trellis = Trellis(self.model)
        self.reset()

    def reset(self) -> None:
        self._trellis.reset()
        self._original = np.zeros(_INITIAL, dtype=ONSET_DTYPE)
        self._routed = Routed(
            np.zeros(_INITIAL, dtype=ONSET_DTYPE),
            np.full(_INITIAL, -1, np.int16),
            np.full(_INITIAL, NOT_PLAYED, np.int8),
            np.zeros(_INITIAL, bool),
            {},
            {},
        )
        self._strength = np.zeros(_INITIAL, BEAT_DTYPE)
        self._count = 0  # notes held, the first of them the stream's note number _base
        self._base = 0
        self._steps: list[_Step] = []
        self._pending = 0  # index into _steps of the first uncommitted step
        self._kicks: dict[int, tuple[float, int]] = {}

    # -- input ---------------------------------------------------------------------------------

    def process(self, row: np.void) -> list[Decision]:
        """Take one onset (an ONSET_DTYPE record, in time order); return what got committed."""
        i = self._append(row)
        t = float(row["time_s"])
        out = self.advance(t - 1e-12) if self._steps else []
        r = self._routed
        if not r.hand[i]:
            return [*out, self._decision(i), *self.advance(t)]
        last = self._steps[-1] if self._steps else None
        if last is not None and t - last.time_s <= CHORD_WINDOW_S:
            out += self._join(last, i)
        else:
            before = self._trellis.snapshot()
            played, _ = reduce_chord([i], r, self.kit)  # one note: nothing to reduce
            step = _Step([i], tuple(played), t, before)
            self._steps.append(step)
            feed(self._trellis, r, step.played, self._strength)
        return out + self.advance(t)

    def advance(self, now_s: float) -> list[Decision]:
        """Commit every hand note whose lookahead has passed by ``now_s``."""
        due = self._pending
        while due < len(self._steps) and self._steps[due].time_s + self.lookahead_s <= now_s:
            due += 1
        return self._commit(due)

    def provisional(self, index: int) -> tuple[int, int]:
        """The limb and piece onset ``index`` has now: its decision when made, else what the
        cheapest path so far gives it (what a lookahead of 0 would commit now);
        (NOT_PLAYED, -1) for an index not seen (or dropped, see the module docstring)."""
        r = self._routed
        index -= self._base
        if not 0 <= index < self._count:
            return NOT_PLAYED, -1
        partner = r.merged.get(index)
        if partner is not None and r.limb[partner] == NOT_PLAYED:
            return self.provisional(self._base + partner)[0], int(r.piece[index])
        if not r.hand[index] or r.limb[index] != NOT_PLAYED:
            return int(r.limb[index]), int(r.piece[index])
        path = self._trellis.best_path(self._pending)
        for k in range(self._pending, len(self._steps)):
            played = self._steps[k].played
            if index in played:
                h = hand_of(int(path[k - self._pending]), self.model.pieces)
                hand = h if played[0] == index else 1 - h
                return LIMB_CODE[Limb.RH if hand == 0 else Limb.LH], int(r.piece[index])
        return NOT_PLAYED, int(r.piece[index])  # left out of its chord (so far)

    def flush(self) -> list[Decision]:
        """End of stream: commit everything still pending."""
        return self._commit(len(self._steps))

    # -- internals -----------------------------------------------------------------------------

    def _append(self, row: np.void) -> int:
        if self._count == self._original.size and not self.keep_onsets:
            self._compact()
        i = self._count
        if i == self._original.size:
            self._grow()
        self._count += 1
        r = self._routed
        self._original[i] = row
        r.onsets[i] = row
        code = int(row["instrument"])
        p = int(self._table[code])
        r.piece[i] = p
        r.limb[i] = NOT_PLAYED
        r.hand[i] = False
        if p < 0:
            r.reasons[i] = f"the kit {self.kit.name!r} has no piece for {INSTRUMENTS[code]}"
            return i
        piece = self.kit.pieces[p]
        pedal = int(row["zone"]) == _PEDAL_ZONE or int(row["hihat"]) == _PEDAL_HIHAT
        if piece.kind is PieceKind.KICK or (piece.kind is PieceKind.HIHAT and pedal):
            limb = foot_limb(piece, int(row["zone"]), int(row["hihat"]))
            if piece.kind is PieceKind.KICK:
                t = float(row["time_s"])
                limb = kick_foot(piece, t, limb, self._kicks.get(p))
                self._kicks[p] = (t, LIMB_CODE[limb])
            r.limb[i] = LIMB_CODE[limb]
            return i
        r.hand[i] = True
        if self.beat_s is not None:
            self._strength[i] = beat_features_at(float(row["time_s"]), self.beat_s)
        return i

    def _grow(self) -> None:
        n = self._original.size * 2
        r = self._routed

        def grow(a: np.ndarray, fill: object) -> np.ndarray:
            out = np.full(n, fill, dtype=a.dtype) if a.dtype.names is None else np.zeros(n, a.dtype)
            out[: a.size] = a
            return out

        self._original = grow(self._original, 0)
        self._routed = Routed(
            grow(r.onsets, 0),
            grow(r.piece, -1),
            grow(r.limb, NOT_PLAYED),
            grow(r.hand, False),
            r.reasons,
            r.merged,
        )
        self._strength = grow(self._strength, 0)

    def _compact(self) -> None:
        """Drop the notes before the first one a step still holds (the arrays grow only when
        more than half of them is still needed)."""
        lo = min((min(s.notes) for s in self._steps), default=self._count)
        if lo < self._original.size // 2:
            return
        n = self._count - lo
        r = self._routed
        for a in (self._original, r.onsets, r.piece, r.limb, r.hand, self._strength):
            a[:n] = a[lo : self._count]
        reasons = {k - lo: v for k, v in r.reasons.items() if k >= lo}
        r.reasons.clear()
        r.reasons.update(reasons)
        merged = {k - lo: v - lo for k, v in r.merged.items() if k >= lo}
        r.merged.clear()
        r.merged.update(merged)
        for s in self._steps:
            s.notes = [j - lo for j in s.notes]
            s.played = tuple(j - lo for j in s.played)
        self._count = n
        self._base += lo

    def _restore_note(self, i: int) -> None:
        r = self._routed
        r.onsets[i] = self._original[i]
        r.hand[i] = True
        r.limb[i] = NOT_PLAYED
        r.reasons.pop(i, None)
        r.merged.pop(i, None)

    def _join(self, step: _Step, i: int) -> list[Decision]:
        """A hand note joins the last chord; redo that step of the recursion if it can."""
        r = self._routed
        step.notes.append(i)
        if not step.committed:
            self._trellis.restore(step.before)
            for j in step.notes:
                self._restore_note(j)
            played, why = reduce_chord(step.notes, r, self.kit)
            r.reasons.update(why)
            step.played = tuple(played)
            feed(self._trellis, r, step.played, self._strength)
            return []
        if len(step.played) == 2:  # both hands committed: the pedal or a merge
            r.hand[i] = False
            if to_pedal(r, i, self.kit):
                r.reasons[i] = "hi-hat played with the pedal: both hands were already committed"
            else:
                merge_into(r, i, step.played)
                r.reasons[i] = (
                    "merged: both hands were already committed at this instant; "
                    "a flam of the nearest stroke's hand"
                )
            return [self._decision(i)]
        first = step.played[0]
        p = int(r.piece[i])
        if int(r.piece[first]) == p and self.kit.pieces[p].kind is PieceKind.HIHAT:
            # one hand on a hi-hat at a time (see prepare.reduce_chord)
            merge_into(r, i, (first,))
            r.reasons[i] = "merged: one hi-hat stroke at a time; a double stroke of its hand"
            return [self._decision(i)]
        # one hand committed: the newcomer takes the other
        forced = 0 if int(r.limb[first]) == _RH else 1
        self._trellis.restore(step.before)
        step.played = (first, i)
        feed(self._trellis, r, step.played, self._strength, forced)
        state = int(np.argmin(self._trellis.value))
        apply_step(r.limb, step.played, state, self.model.pieces)
        self._settle(len(self._steps) - 1, state)
        return [self._decision(i)]

    def _commit(self, due: int) -> list[Decision]:
        if due <= self._pending:
            return []
        trellis = self._trellis
        path = trellis.best_path(self._pending)
        out: list[Decision] = []
        n = self.model.pieces
        for k in range(self._pending, due):
            step = self._steps[k]
            apply_step(self._routed.limb, step.played, int(path[k - self._pending]), n)
            apply_merged(self._routed, step.notes)
            step.committed = True
            out += [self._decision(j) for j in step.notes]
        self._settle(due - 1, int(path[due - 1 - self._pending]))
        last = self._steps[-1]
        if self._pending <= len(self._steps) - 2 < due:  # keep a redo of the last step in line
            keep = int(path[len(self._steps) - 2 - self._pending])
            mask = np.ones_like(last.before.value, dtype=bool)
            mask[keep] = False
            last.before.value[mask] = np.inf
        self._pending = due
        self._forget(min(due, len(self._steps) - 1))
        return out

    def _forget(self, count: int) -> None:
        """Drop the first ``count`` steps (committed; not the last) so memory stays bounded."""
        if count <= 0:
            return
        del self._steps[:count]
        del self._trellis.backpointers[:count]
        self._pending -= count
        last = self._steps[-1]
        last.before = replace(last.before, steps=last.before.steps - count)

    def _settle(self, k: int, state: int) -> None:
        """Drop every current path whose state at step ``k`` is not ``state``."""
        trellis = self._trellis
        anc = np.arange(2 * self.model.pieces)
        for j in range(len(trellis.backpointers) - 1, k, -1):
            anc = trellis.backpointers[j][anc]
        trellis.value[anc != state] = np.inf

    def _decision(self, i: int) -> Decision:
        r = self._routed
        pedal = bool(r.onsets["zone"][i] != self._original["zone"][i])
        return Decision(self._base + i, int(r.limb[i]), int(r.piece[i]), r.reasons.get(i), pedal)

    def onsets(self) -> np.ndarray:
        """Every onset so far, after substitutions (a copy); with ``keep_onsets=False``, those
        still held."""
        return self._routed.onsets[: self._count].copy()


def stick_online(
    onsets: np.ndarray, kit: Kit, lookahead_s: float, *, beat_s: np.ndarray | None = None
) -> Sticking:
    """Run :class:`OnlineSticker` over a whole onset array; the result as a :class:`Sticking`."""
    sticker = OnlineSticker(kit, lookahead_s, beat_s=beat_s)
    decisions: list[Decision] = []
    for row in onsets:
        decisions += sticker.process(row)
    decisions += sticker.flush()
    limb = np.full(onsets.size, NOT_PLAYED, dtype=np.int8)
    piece = np.full(onsets.size, -1, dtype=np.int16)
    reasons: dict[int, str] = {}
    for d in decisions:
        limb[d.index], piece[d.index] = d.limb, d.piece
        if d.reason is not None:
            reasons[d.index] = d.reason
    return Sticking(sticker.onsets(), limb, piece, reasons, "optimal", kit.name)
