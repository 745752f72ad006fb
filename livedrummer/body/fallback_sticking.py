"""A deliberately simple limb assignment, used until :mod:`livedrummer.sticking` lands.

Each onset goes to the limb the kit prefers for its piece and zone
(:meth:`~livedrummer.kit.Piece.limb_for`). A hand note closer than the piece's
``min_time_gap_s`` to that hand's previous note goes to the other hand if the other hand is
free and reaches the zone; failing that, to whichever reaching hand has waited longer, as
long as it is at least :data:`HARD_MIN_GAP_S` free; otherwise the note is not played (with
its reason). Feet keep their pedal. This is a stand-in with no look-ahead, pairs or flams.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit import Kit
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED, Sticking
from livedrummer.vocabulary import HIHATS, INSTRUMENTS, ZONES, Limb

HARD_MIN_GAP_S = 0.03  # one hand never strikes twice faster than this
FOOT_MIN_GAP_S = 0.03


def fallback_sticking(onsets: np.ndarray, kit: Kit, hand_ok: np.ndarray | None = None
                      ) -> Sticking:  # fmt: skip
    """Limb per onset; ``hand_ok`` (2, P, Z) from :class:`~livedrummer.body.rig.Rig`."""
    n = onsets.size
    limb = np.full(n, NOT_PLAYED, dtype=np.int8)
    piece_idx = np.full(n, -1, dtype=np.int16)
    reasons: dict[int, str] = {}
    index = {p.name: i for i, p in enumerate(kit.pieces)}
    route: dict[int, int] = {}
    for code, name in enumerate(INSTRUMENTS):
        p = kit.resolve(name)
        route[code] = -1 if p is None else index[p.name]
    last = [-1e9, -1e9, -1e9, -1e9]
    times = onsets["time_s"].tolist()
    inst = onsets["instrument"].tolist()
    zones = onsets["zone"].tolist()
    hats = onsets["hihat"].tolist()
    for i in range(n):
        pi = route[inst[i]]
        if pi < 0:
            reasons[i] = f"kit {kit.name!r} has no piece for {INSTRUMENTS[inst[i]]!r}"
            continue
        piece = kit.pieces[pi]
        t = times[i]
        want = LIMB_CODE[piece.limb_for(ZONES[zones[i]], HIHATS[hats[i]])]
        if want >= 2:
            if t - last[want] < FOOT_MIN_GAP_S:
                reasons[i] = f"{Limb(('RF', 'LF')[want - 2]).value} busy"
                continue
            chosen = want
        else:
            other = 1 - want
            reach = [True, True] if hand_ok is None else [
                bool(hand_ok[0, pi, zones[i]]), bool(hand_ok[1, pi, zones[i]])]  # fmt: skip
            gap = piece.min_time_gap_s
            if t - last[want] >= gap and reach[want]:
                chosen = want
            elif t - last[other] >= gap and reach[other]:
                chosen = other
            else:
                options = [h for h in (want, other) if reach[h] and t - last[h] >= HARD_MIN_GAP_S]
                if not options:
                    reasons[i] = "both hands busy"
                    continue
                chosen = min(options, key=lambda h: last[h])
        limb[i] = chosen
        piece_idx[i] = pi
        last[chosen] = t
    return Sticking(onsets, limb, piece_idx, reasons, "fallback", kit.name)
