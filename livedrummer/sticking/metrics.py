"""How a sticking is judged: crossings, same-hand-too-fast, dropped notes, accuracy.

Defined once here, used by the tests, the benchmark and (through :func:`crossing_depth`) the
cost model, so "better" means the same thing everywhere.

*Too fast*: a hand stroke that follows the same hand's previous stroke sooner than the piece's
``min_time_gap_s`` (moving between two pieces: the smaller of their two gaps). A second stroke
on the *same* piece may come after half that gap (a double stroke: the stick rebounds), but not
twice in a row.

*Crossing*: at a hand stroke, the stance is this hand's piece and the piece the other hand
struck last (up to the end of this stroke's chord, see :mod:`.prepare`), if it did so within
:data:`STANCE_WINDOW_S` (a hand idle longer has gone back to
rest). The arms are crossed when the right hand's piece lies left of the left hand's (by more
than :data:`CROSS_TOL_M` in x). A crossing is *conventional*, and not counted, when the hand
reaching over is the lead hand (right on a right-handed kit) on a cymbal and the other hand is on
a drum below it, no further than :data:`CONVENTIONAL_REACH_M` across: the right hand on the
hi-hat over the left on the snare, or on a crash just beyond the hi-hat. Anything else (right
hand on the high tom while the left plays the floor tom) counts. Because
everything is measured from piece positions and the kit's handedness, a mirrored kit is judged
by the mirrored rule.

:func:`hard_notes` says, note by note and in words, which strokes are too fast for one hand or
made with the arms crossed, as SMED showed the parts of a score too hard to play; the sticking
sheet, ``sticking --json`` and ``check --json`` report it.

A merged note (:func:`~.result.merged_notes`: a flam or double stroke folded into another
stroke of its hand) is not a stroke of its own: it is neither judged too fast nor crossed, and
it is not dropped; :func:`merged` counts them.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking.prepare import chords
from livedrummer.sticking.result import LIMB_CODE, LIMBS, NOT_PLAYED, Sticking, merged_notes

STANCE_WINDOW_S = 0.5
CROSS_TOL_M = 0.10
CONVENTIONAL_REACH_M = 0.40
DOUBLE_STROKE_FACTOR = 0.5

_RH = LIMB_CODE[Limb.RH]
_LH = LIMB_CODE[Limb.LH]


def crossing_depth(kit: Kit) -> tuple[np.ndarray, np.ndarray]:
    """For every (right-hand piece, left-hand piece): how far crossed (m) and if conventional."""
    x = np.array([p.position_m[0] for p in kit.pieces])
    cymbal = np.array([p.kind.is_cymbal for p in kit.pieces])
    depth = x[None, :] - x[:, None]  # [r, l]: > 0 when the right hand is left of the left
    depth = np.where(depth > CROSS_TOL_M, depth, 0.0)
    if kit.handedness == "right":
        conventional = cymbal[:, None] & ~cymbal[None, :]
    else:
        conventional = ~cymbal[:, None] & cymbal[None, :]
    conventional &= depth <= CONVENTIONAL_REACH_M
    return depth, conventional


def too_fast(sticking: Sticking, kit: Kit) -> np.ndarray:
    """Per onset: a hand stroke too soon after the same hand's previous one (see above)."""
    return _too_fast(sticking, kit)[0]


def _too_fast(sticking: Sticking, kit: Kit) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(too fast, seconds since the same hand's last stroke, seconds it needs) per onset."""
    n = sticking.limb.size
    out = np.zeros(n, dtype=bool)
    since, needs = np.full(n, np.nan), np.full(n, np.nan)
    gap = np.array([p.min_time_gap_s for p in kit.pieces])
    t = sticking.onsets["time_s"]
    limb = _stroke_limbs(sticking)
    for hand in (_RH, _LH):
        idx = np.flatnonzero(limb == hand)
        if idx.size < 2:
            continue
        dt = np.diff(t[idx])
        pc = sticking.piece[idx]
        same = pc[1:] == pc[:-1]
        g = np.where(same, gap[pc[1:]], np.minimum(gap[pc[1:]], gap[pc[:-1]]))
        double = same & (dt >= DOUBLE_STROKE_FACTOR * g) & (dt < g)
        repeated = double & np.concatenate(([False], double[:-1]))
        out[idx[1:]] = ((dt < g) & ~double) | repeated
        since[idx[1:]] = dt
        needs[idx[1:]] = np.where(same & ~repeated, DOUBLE_STROKE_FACTOR * g, g)
    return out, since, needs


def crossings(sticking: Sticking, kit: Kit) -> np.ndarray:
    """Per onset: a hand stroke made with the arms unconventionally crossed (see above)."""
    return _crossings(sticking, kit)[0]


def _crossings(sticking: Sticking, kit: Kit) -> tuple[np.ndarray, np.ndarray]:
    """(crossed, the other hand's piece at that stroke or -1) per onset."""
    out = np.zeros(sticking.limb.size, dtype=bool)
    other_piece = np.full(sticking.limb.size, -1, dtype=np.int64)
    t = sticking.onsets["time_s"]
    depth, conventional = crossing_depth(kit)
    bad = (depth > 0) & ~conventional
    limb = _stroke_limbs(sticking)
    hands = np.flatnonzero((limb == _RH) | (limb == _LH))
    chord_end = np.zeros(sticking.limb.size)
    for group in chords(t[hands]):
        chord_end[hands[group]] = t[hands[group[-1]]]
    by_hand = {h: np.flatnonzero(limb == h) for h in (_RH, _LH)}
    for hand, other in ((_RH, _LH), (_LH, _RH)):
        mine, theirs = by_hand[hand], by_hand[other]
        if mine.size == 0 or theirs.size == 0:
            continue
        tt = t[theirs]
        j = np.searchsorted(tt, chord_end[mine], side="right") - 1
        ok = j >= 0
        jj = np.where(ok, j, 0)
        ok &= t[mine] - tt[jj] <= STANCE_WINDOW_S
        mp, op = sticking.piece[mine], sticking.piece[theirs][jj]
        r, lft = (mp, op) if hand == _RH else (op, mp)
        out[mine] = ok & bad[r, lft]
        other_piece[mine] = np.where(ok, op, -1)
    return out, other_piece


def hard_notes(sticking: Sticking, kit: Kit) -> dict[int, str]:
    """Onset index -> why it is hard to play, for every stroke too fast or with arms crossed.

    For example ``too fast for one hand: 40.2 ms after its last stroke, needs 60 ms`` or
    ``arms crossed: RH on tom1 left of LH on hihat``; both, joined by ``; ``, when both hold.
    """
    fast, since, needs = _too_fast(sticking, kit)
    crossed, other = _crossings(sticking, kit)
    out: dict[int, str] = {}
    for i in np.flatnonzero(fast | crossed).tolist():
        why = []
        if fast[i]:
            why.append(
                f"too fast for one hand: {since[i] * 1000:.1f} ms after its last stroke, "
                f"needs {needs[i] * 1000:.3g} ms"
            )
        if crossed[i]:
            mine, theirs = LIMBS[int(sticking.limb[i])], LIMBS[1 - int(sticking.limb[i])]
            here = kit.pieces[int(sticking.piece[i])].name
            there = kit.pieces[int(other[i])].name
            right, left = (
                ((mine, here), (theirs, there))
                if mine is Limb.RH
                else ((theirs, there), (mine, here))
            )
            why.append(
                f"arms crossed: {right[0].value} on {right[1]} left of {left[0].value} on {left[1]}"
            )
        out[i] = "; ".join(why)
    return out


def _stroke_limbs(sticking: Sticking) -> np.ndarray:
    """The limbs with merged notes as not played: the strokes alone."""
    limb = sticking.limb.copy()
    limb[merged_notes(sticking)] = NOT_PLAYED
    return limb


def merged(sticking: Sticking) -> np.ndarray:
    """Per onset: a note merged into another stroke of its hand (a flam or double stroke)."""
    return merged_notes(sticking)


def dropped(sticking: Sticking) -> np.ndarray:
    """Per onset: a note the kit could play but no limb plays."""
    out: np.ndarray = (sticking.limb == NOT_PLAYED) & (sticking.piece >= 0)
    return out


def accuracy(sticking: Sticking, annotated: np.ndarray) -> tuple[int, int]:
    """(matches, total) over the notes a teacher gave to a hand (annotated RH or LH)."""
    mask = (annotated == _RH) | (annotated == _LH)
    return int(np.count_nonzero(sticking.limb[mask] == annotated[mask])), int(mask.sum())
