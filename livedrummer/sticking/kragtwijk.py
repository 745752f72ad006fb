"""Kragtwijk et al.'s two hand-assignment heuristics, as the virtual-drummer paper describes them.

``kragtwijk-basic`` (the paper's Algorithm 3.1): every hand note takes its piece's preferred
hand; then, walking over consecutive triplets of hand notes, the middle one changes hands when
all three share a hand and either interval is within the piece's ``min_time_gap_s``. Only two
hand notes may share an instant: the rest of a chord is deleted (with a reason here).

``kragtwijk-pair`` (§4.2): at most one hi-hat stroke per instant; when three or more hand notes
coincide, the hi-hat moves to the pedal; then each note's hand value is the mean of its values
in the pairs with its previous and its next note, where a pair's values blend the kit's
``pair(a, b)`` and the default hands by ``rho ** dt`` (``dt`` in seconds, so close notes follow
the pair table and distant ones their default hand). The sign of the value picks the hand.

Both are kept as the paper states them, flaws included (two notes of one chord may land on one
hand; arms cross on fast hi-hat/ride exchanges), because they are the baselines ``optimal`` is
measured against. The kit's preferred limbs and pair table mirror with the kit, so both mirror.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb, PieceKind
from livedrummer.sticking.prepare import (
    Routed,
    apply_merged,
    chords,
    lead_hand,
    reduce_chord,
    route,
)
from livedrummer.sticking.result import LIMB_CODE, Sticking

_RH, _LH = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH]
DEFAULT_RHO = 1e-3


def default_hands(kit: Kit) -> np.ndarray:
    """Preferred hand code per piece (a foot-preferred piece falls to the lead hand)."""
    lead = LIMB_CODE[lead_hand(kit)]
    return np.array(
        [LIMB_CODE[p.preferred_limb] if p.preferred_limb.is_hand else lead for p in kit.pieces],
        dtype=np.int8,
    )


def _drop_beyond_two(routed: Routed, reasons: dict[int, str]) -> None:
    hand = np.flatnonzero(routed.hand)
    for group in chords(routed.onsets["time_s"][hand]):
        for i in hand[group[2:]].tolist():
            routed.hand[i] = False
            reasons[i] = "deleted: more than two hand notes at once"


def kragtwijk_basic(onsets: np.ndarray, kit: Kit, *, beat_s: np.ndarray | None = None) -> Sticking:
    """Algorithm 3.1 (see the module docstring); ``beat_s`` is not used."""
    routed = route(onsets, kit)
    reasons = dict(routed.reasons)
    _drop_beyond_two(routed, reasons)
    hand = np.flatnonzero(routed.hand)
    gap = np.array([p.min_time_gap_s for p in kit.pieces])
    h = default_hands(kit)[routed.piece[hand]].tolist()
    t = routed.onsets["time_s"][hand].tolist()
    g = gap[routed.piece[hand]].tolist()
    for k in range(1, len(h) - 1):
        if h[k - 1] == h[k] == h[k + 1] and (
            t[k] - t[k - 1] <= g[k - 1] or t[k + 1] - t[k] <= g[k + 1]
        ):
            h[k] = _LH if h[k] == _RH else _RH
    routed.limb[hand] = h
    return Sticking(routed.onsets, routed.limb, routed.piece, reasons, "kragtwijk-basic", kit.name)


def _one_hihat_per_instant(routed: Routed, kit: Kit, reasons: dict[int, str]) -> None:
    hand = np.flatnonzero(routed.hand)
    hats = {i for i, p in enumerate(kit.pieces) if p.kind is PieceKind.HIHAT}
    for group in chords(routed.onsets["time_s"][hand]):
        members = hand[group].tolist()
        on_hat = [i for i in members if int(routed.piece[i]) in hats]
        for i in on_hat[1:]:
            routed.hand[i] = False
            reasons[i] = "deleted: only one hi-hat stroke at a time"
        rest = [i for i in members if routed.hand[i]]
        if len(rest) > 2 and on_hat:
            _, why = reduce_chord(rest, routed, kit)  # moves the hi-hat to the pedal first
            reasons.update(why)


def kragtwijk_pair(
    onsets: np.ndarray, kit: Kit, *, beat_s: np.ndarray | None = None, rho: float = DEFAULT_RHO
) -> Sticking:
    """§4.2 (see the module docstring); ``beat_s`` is not used."""
    routed = route(onsets, kit)
    reasons = dict(routed.reasons)
    _one_hihat_per_instant(routed, kit, reasons)
    _drop_beyond_two(routed, reasons)
    hand = np.flatnonzero(routed.hand)
    pc = routed.piece[hand]
    default = np.where(default_hands(kit)[pc] == _RH, 1.0, -1.0)
    names = [p.name for p in kit.pieces]
    table = np.array([[kit.pair(a, b) for b in names] for a in names])
    value = default.copy()
    if hand.size > 1:
        dt = np.diff(routed.onsets["time_s"][hand])
        w = rho**dt
        pair = table[pc[:-1], pc[1:]]
        first = w * pair + (1 - w) * default[:-1]  # value of e1 in pair (e1, e2)
        second = w * -pair + (1 - w) * default[1:]  # value of e2
        total = np.zeros(hand.size)
        count = np.zeros(hand.size)
        total[:-1] += first
        count[:-1] += 1
        total[1:] += second
        count[1:] += 1
        value = total / count
        value = np.where(value == 0.0, default, value)
    routed.limb[hand] = np.where(value > 0, _RH, _LH)
    apply_merged(routed)
    return Sticking(routed.onsets, routed.limb, routed.piece, reasons, "kragtwijk-pair", kit.name)
