"""SMED's five-pass limb assignment (the SMED thesis, its hand-assignment figure).

1. Fixed limbs: the feet (done by :func:`~.prepare.route`) and the ride, the lead hand's.
2. Forward: a note quicker than the threshold after the previous one goes to the other hand
   when the previous one is assigned; two quick notes on different drums, both unassigned, go
   to the hands on their sides (the left hand to the piece further left).
3. Backward, the same, so that hands lead properly into runs; two quick notes on one drum take
   the lead hand on the one nearer the 8th/16th/32nd grid (needs ``beat_s``; else the earlier).
4. Cymbals (hi-hat, crashes) and the floor tom not yet assigned go to the lead hand.
5. Everything left alternates with the previous hand note.

The threshold is the later note's ``min_time_gap_s``. "Left" and "right" come from the piece
positions, and the lead hand from the kit's handedness, so SMED mirrors with the kit. The thesis
does not say what happens to a chord of three hand notes; here the shared drummer's rule
(:func:`~.prepare.reduce_chord`) resolves it first. Like the thesis, no geometry beyond
left/right and no arm model: its known flaw is crossings when a run changes drums.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb, PieceKind
from livedrummer.sticking.prepare import (
    apply_merged,
    beat_position,
    chords,
    lead_hand,
    reduce_chord,
    route,
)
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED, Sticking

_RH, _LH = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH]
_NONE = NOT_PLAYED


def _other(h: int) -> int:
    return _LH if h == _RH else _RH


def _grid_level(times: np.ndarray, beat_s: np.ndarray | None) -> np.ndarray:
    """3 for a note on the 8th grid, 2 on the 16th, 1 on the 32nd, else 0."""
    out = np.zeros(times.size)
    if beat_s is None or beat_s.size < 2 or times.size == 0:
        return out
    pos = beat_position(times, beat_s)
    for level, div in ((1, 8), (2, 4), (3, 2)):
        scaled = pos * div
        out[np.abs(scaled - np.round(scaled)) < 0.15] = level
    return out


def smed(onsets: np.ndarray, kit: Kit, *, beat_s: np.ndarray | None = None) -> Sticking:
    """The five passes (see the module docstring)."""
    routed = route(onsets, kit)
    reasons = dict(routed.reasons)
    hand_all = np.flatnonzero(routed.hand)
    for group in chords(routed.onsets["time_s"][hand_all]):
        reasons.update(reduce_chord(hand_all[group].tolist(), routed, kit)[1])
    hand = np.flatnonzero(routed.hand)
    lead = LIMB_CODE[lead_hand(kit)]
    pcs = routed.piece[hand].tolist()
    t = routed.onsets["time_s"][hand].tolist()
    x = [kit.pieces[p].position_m[0] for p in pcs]
    gap = [kit.pieces[p].min_time_gap_s for p in pcs]
    near = _grid_level(routed.onsets["time_s"][hand], beat_s).tolist()
    n = len(pcs)
    h = [lead if kit.pieces[p].kind is PieceKind.RIDE else _NONE for p in pcs]
    lo, hi = (_LH, _RH)

    def pair(a: int, b: int, same_rule: bool) -> None:
        # a and b are quick neighbours, b unassigned
        if h[a] != _NONE:
            h[b] = _other(h[a])
        elif x[a] != x[b]:  # different drums, side by side
            left, right = (a, b) if x[a] < x[b] else (b, a)
            h[left], h[right] = lo, hi
        elif same_rule:  # one drum (or two in line): the lead hand on the stronger beat
            first, second = (a, b) if near[a] >= near[b] else (b, a)
            h[first], h[second] = lead, _other(lead)

    for k in range(1, n):  # pass 2
        if h[k] == _NONE and t[k] - t[k - 1] < gap[k]:
            pair(k - 1, k, same_rule=False)
    for k in range(n - 2, -1, -1):  # pass 3
        if h[k] == _NONE and t[k + 1] - t[k] < gap[k + 1]:
            pair(k + 1, k, same_rule=True)
    toms = [i for i, p in enumerate(kit.pieces) if p.kind is PieceKind.TOM]
    floor = min(toms, key=lambda i: kit.pieces[i].position_m[2]) if toms else -1
    fixed = (PieceKind.HIHAT, PieceKind.CRASH, PieceKind.SPLASH, PieceKind.CHINA)
    for k in range(n):  # pass 4
        if h[k] == _NONE and (kit.pieces[pcs[k]].kind in fixed or pcs[k] == floor):
            h[k] = lead
    for k in range(n):  # pass 5
        if h[k] == _NONE:
            h[k] = _other(h[k - 1]) if k > 0 else lead
    routed.limb[hand] = h
    apply_merged(routed)
    return Sticking(routed.onsets, routed.limb, routed.piece, reasons, "smed", kit.name)
