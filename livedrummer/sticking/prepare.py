"""What every strategy does first: route notes to pieces and feet, and group hand notes in time.

Limb assignment is only interesting for the hands. The feet are decided by the kit alone (the
kick is the kick foot's, a hi-hat pedal note the hi-hat foot's, both mirror with the kit), and a
note whose instrument the kit lacks cannot be played at all. Doing this once, here, keeps the
strategies comparable: they differ only in how they share the remaining notes between two hands.

Hand notes closer together than :data:`CHORD_WINDOW_S` count as one instant (a *chord*): a real
performance never lands two strokes on the same millisecond, and a drummer playing crash and
snare "together" spreads them by a few milliseconds. A chord of more than two hand notes cannot
be played as separate strokes; :func:`reduce_chord` resolves it as a drummer would (the hi-hat
moves to the pedal), and a note still beyond two hands, or a second stroke on one hi-hat, is
*merged*: it follows the kept note nearest to it in time (on the same piece if one is), as a
flam or double stroke of that note's hand, shortened to the gap (:attr:`Routed.merged`,
:func:`apply_merged`). Nothing a user played is lost: a merged note keeps its own onset, gets
a limb, and has its reason. Its limb is known once its partner's is, so every strategy calls
:func:`apply_merged` after deciding the hands.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Limb, PieceKind, Zone
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED

#: Hand notes within this many seconds of a chord's first note belong to that chord.
CHORD_WINDOW_S = 0.015

_PEDAL_ZONE = ZONES.index(Zone.PEDAL)
_PEDAL_HIHAT = HIHATS.index(HiHat.PEDAL)


@dataclass(frozen=True)
class Routed:
    """Pieces and feet decided; ``hand`` marks the notes left for the hands (a mutable start)."""

    onsets: np.ndarray  # a copy: substitutions edit it
    piece: np.ndarray  # int16 index into kit.pieces, -1 when the kit lacks the instrument
    limb: np.ndarray  # int8: feet filled in, everything else NOT_PLAYED
    hand: np.ndarray  # bool: notes the hands must play
    reasons: dict[int, str]
    #: merged note -> the kept note of its chord whose hand strikes it too (see the module doc)
    merged: dict[int, int] = field(default_factory=dict)


def piece_table(kit: Kit) -> np.ndarray:
    """Piece index (into ``kit.pieces``) for every instrument code, -1 where the kit has none."""
    index = {p.name: i for i, p in enumerate(kit.pieces)}
    out = np.full(len(INSTRUMENTS), -1, dtype=np.int16)
    for code, name in enumerate(INSTRUMENTS):
        piece = kit.resolve(name)
        if piece is not None:
            out[code] = index[piece.name]
    return out


def is_pedal_stroke(onsets: np.ndarray, piece: np.ndarray, kit: Kit) -> np.ndarray:
    """True where a note is played by a foot: kick strokes and hi-hat pedal strokes."""
    kinds = np.array([p.kind is PieceKind.KICK for p in kit.pieces] + [False])
    hats = np.array([p.kind is PieceKind.HIHAT for p in kit.pieces] + [False])
    pedal = (onsets["zone"] == _PEDAL_ZONE) | (onsets["hihat"] == _PEDAL_HIHAT)
    out: np.ndarray = kinds[piece] | (hats[piece] & pedal)
    return out


def foot_limb(piece: Piece, zone: int, hihat: int) -> Limb:
    return piece.limb_for(ZONES[zone], HIHATS[hihat])


def route(onsets: np.ndarray, kit: Kit) -> Routed:
    """Decide pieces and feet; mark hand notes (see the module docstring)."""
    on = onsets.copy()
    piece = piece_table(kit)[on["instrument"]] if on.size else np.zeros(0, np.int16)
    limb = np.full(on.size, NOT_PLAYED, dtype=np.int8)
    reasons: dict[int, str] = {}
    for i in np.flatnonzero(piece < 0).tolist():
        reasons[i] = f"the kit {kit.name!r} has no piece for {INSTRUMENTS[on['instrument'][i]]}"
    foot = is_pedal_stroke(on, piece, kit) & (piece >= 0)
    last_kick: dict[int, tuple[float, int]] = {}
    for i in np.flatnonzero(foot).tolist():
        p = kit.pieces[int(piece[i])]
        chosen = foot_limb(p, int(on["zone"][i]), int(on["hihat"][i]))
        if p.kind is PieceKind.KICK:
            chosen = kick_foot(p, float(on["time_s"][i]), chosen, last_kick.get(int(piece[i])))
            last_kick[int(piece[i])] = (float(on["time_s"][i]), LIMB_CODE[chosen])
        limb[i] = LIMB_CODE[chosen]
    hand = (piece >= 0) & ~foot
    return Routed(on, piece.astype(np.int16), limb, hand, reasons)


def kick_foot(p: Piece, t: float, usual: Limb, last: tuple[float, int] | None) -> Limb:
    """The usual foot, or the other one on a double pedal when the kick comes too fast."""
    if not p.double_pedal or last is None:
        return usual
    last_t, last_limb = last
    if t - last_t < p.min_time_gap_s and last_limb == LIMB_CODE[usual]:
        return usual.mirrored
    return usual


def chords(times: np.ndarray, window_s: float = CHORD_WINDOW_S) -> list[np.ndarray]:
    """Group positions of ascending ``times`` into chords (see the module docstring)."""
    if times.size == 0:
        return []
    starts = [0]
    first = float(times[0])
    for k, t in enumerate(times.tolist()):
        if t - first > window_s:
            starts.append(k)
            first = t
    bounds = [*starts, times.size]
    idx = np.arange(times.size)
    return [idx[a:b] for a, b in pairwise(bounds)]


def reduce_chord(members: list[int], routed: Routed, kit: Kit) -> tuple[list[int], dict[int, str]]:
    """Keep at most two separate hand strokes in one chord, and one hand on each hi-hat.

    Two hands cannot strike one hi-hat at one instant (Kragtwijk et al. §4.2: only one hi-hat
    event at a time), so of several strokes on the same hi-hat the loudest is the stroke (the
    first of equals) and the others merge into it (a double stroke of its hand). Then, while
    more than two notes remain, a hi-hat stroke moves to the pedal (its onset's zone becomes
    ``pedal``, its limb the hi-hat foot); if more than two still remain, the quietest notes
    merge into the kept note nearest in time (:func:`merge_into`). Returns the notes the hands
    play as strokes and the reasons for every changed note. ``routed`` is updated in place.
    """
    keep = list(members)
    reasons: dict[int, str] = {}
    on = routed.onsets
    if len(keep) > 1:
        for i, loudest in _second_hihat_strokes(keep, routed, kit):
            keep.remove(i)
            routed.hand[i] = False
            routed.merged[i] = loudest
            reasons[i] = "merged: one hi-hat stroke at a time; a double stroke of the louder's hand"
    if len(keep) <= 2:
        return keep, reasons
    for i in list(keep):
        if len(keep) > 2 and to_pedal(routed, i, kit):
            keep.remove(i)
            reasons[i] = "hi-hat played with the pedal: more than two hand notes at once"
    for i in members:  # a double stroke of a hi-hat stroke that went to the pedal
        if i in routed.merged and routed.merged[i] not in keep:
            merge_into(routed, i, keep)
            reasons[i] = (
                "merged: one hi-hat stroke at a time, and that one went to the pedal; "
                "a flam of the nearest stroke's hand"
            )
    extra: list[int] = []
    while len(keep) > 2:
        quietest = min(keep, key=lambda j: (int(on["velocity"][j]), -j))
        keep.remove(quietest)
        extra.append(quietest)
    for i in extra:
        merge_into(routed, i, keep)
        reasons[i] = (
            "merged: more than two hand notes at once, and this the quietest; "
            "a flam of the nearest stroke's hand"
        )
    return keep, reasons


def merge_into(routed: Routed, i: int, kept: list[int] | tuple[int, ...]) -> int:
    """Merge hand note ``i`` into the note of ``kept`` on its piece, else the nearest in time;
    returns that partner. Its limb is the partner's, written by :func:`apply_merged`."""
    t = float(routed.onsets["time_s"][i])
    p = int(routed.piece[i])
    times = routed.onsets["time_s"]
    partner = min(kept, key=lambda j: (int(routed.piece[j]) != p, abs(float(times[j]) - t), j))
    routed.hand[i] = False
    routed.limb[i] = routed.limb[partner]
    routed.merged[i] = partner
    for j, into in routed.merged.items():  # a note merged into i follows i: no chains
        if into == i:
            routed.merged[j] = partner
            routed.limb[j] = routed.limb[partner]
    return partner


def apply_merged(routed: Routed, notes: list[int] | None = None) -> None:
    """Give every merged note (of ``notes``, else all) its partner's limb."""
    merged = routed.merged
    for i in merged if notes is None else (j for j in notes if j in merged):
        routed.limb[i] = routed.limb[merged[i]]


def _second_hihat_strokes(members: list[int], routed: Routed, kit: Kit) -> list[tuple[int, int]]:
    """Strokes of a chord on a hi-hat that another, louder stroke of it already plays, each
    with that louder stroke."""
    on_hat: dict[int, list[int]] = {}
    for i in members:
        p = int(routed.piece[i])
        if kit.pieces[p].kind is PieceKind.HIHAT:
            on_hat.setdefault(p, []).append(i)
    out: list[tuple[int, int]] = []
    for strokes in on_hat.values():
        if len(strokes) > 1:
            loudest = max(strokes, key=lambda j: (int(routed.onsets["velocity"][j]), -j))
            out += [(j, loudest) for j in strokes if j != loudest]
    return out


def to_pedal(routed: Routed, i: int, kit: Kit) -> bool:
    """Move hand note ``i`` to the hi-hat pedal if it is a hi-hat stroke that has a pedal."""
    p = kit.pieces[int(routed.piece[i])]
    if p.kind is not PieceKind.HIHAT or Zone.PEDAL not in p.zones:
        return False
    routed.onsets["zone"][i] = _PEDAL_ZONE
    routed.onsets["hihat"][i] = _PEDAL_HIHAT
    routed.limb[i] = LIMB_CODE[foot_limb(p, _PEDAL_ZONE, _PEDAL_HIHAT)]
    routed.hand[i] = False
    return True


def beat_position(times: np.ndarray, beat_s: np.ndarray) -> np.ndarray:
    """Fractional beat index of each time (linear between beats of the grid)."""
    i = np.clip(np.searchsorted(beat_s, times, side="right") - 1, 0, beat_s.size - 2)
    out: np.ndarray = i + (times - beat_s[i]) / (beat_s[i + 1] - beat_s[i])
    return out


def beat_strength(times: np.ndarray, beat_s: np.ndarray | None, tol: float = 0.08) -> np.ndarray:
    """1 on a beat, 0.5 on the off-beat eighth, else 0 (all 0 without a grid)."""
    out = np.zeros(times.size)
    if beat_s is None or beat_s.size < 2 or times.size == 0:
        return out
    pos = beat_position(times, beat_s)
    frac = pos - np.floor(pos)
    out[(frac < tol) | (frac > 1 - tol)] = 1.0
    out[np.abs(frac - 0.5) < tol] = 0.5
    return out


#: Per hand note, what the beat grid says of it (:func:`beat_features`): ``strength`` as
#: :func:`beat_strength`; ``sixth_s``, a sixth of the local beat where the note lies on the
#: sixteenth-triplet grid (0 elsewhere); ``grouping``, its weight in that grid's groupings of
#: three (1 on the beat, 0.5 on the second and third eighth-triplet, 0 on the notes between).
BEAT_DTYPE = np.dtype([("strength", "f8"), ("sixth_s", "f8"), ("grouping", "f8")])
#: How near a sixteenth-triplet a note must be, in sixths of a beat (at 100 bpm: 20 ms).
TRIPLET_TOL = 0.2


def beat_features(times: np.ndarray, beat_s: np.ndarray | None, tol: float = 0.08) -> np.ndarray:
    """:data:`BEAT_DTYPE` per time (all 0 without a grid)."""
    out = np.zeros(times.size, BEAT_DTYPE)
    out["strength"] = beat_strength(times, beat_s, tol)
    if beat_s is None or beat_s.size < 2 or times.size == 0:
        return out
    i = np.clip(np.searchsorted(beat_s, times, side="right") - 1, 0, beat_s.size - 2)
    pos = beat_position(times, beat_s)
    sixth = (pos - np.floor(pos)) * 6.0
    k = np.round(sixth)
    on = np.abs(sixth - k) < TRIPLET_TOL
    out["sixth_s"] = np.where(on, (beat_s[i + 1] - beat_s[i]) / 6.0, 0.0)
    out["grouping"] = np.where(on & (k % 2 == 0), np.where(k % 6 == 0, 1.0, 0.5), 0.0)
    return out


def beat_features_at(
    time_s: float, beat_s: np.ndarray | None, tol: float = 0.08
) -> tuple[float, float, float]:
    """:func:`beat_features` of one time, as a (strength, sixth_s, grouping) tuple."""
    strength = beat_strength_at(time_s, beat_s, tol)
    if beat_s is None or beat_s.size < 2:
        return strength, 0.0, 0.0
    i = min(max(bisect_right(beat_s, time_s) - 1, 0), beat_s.size - 2)
    a, b = float(beat_s[i]), float(beat_s[i + 1])
    pos = i + (time_s - a) / (b - a)
    sixth = (pos - math.floor(pos)) * 6.0
    k = round(sixth)
    if abs(sixth - k) >= TRIPLET_TOL:
        return strength, 0.0, 0.0
    grouping = (1.0 if k % 6 == 0 else 0.5) if k % 2 == 0 else 0.0
    return strength, (b - a) / 6.0, grouping


def beat_strength_at(time_s: float, beat_s: np.ndarray | None, tol: float = 0.08) -> float:
    """:func:`beat_strength` of one time, without building arrays (for the online form)."""
    if beat_s is None or beat_s.size < 2:
        return 0.0
    i = min(max(bisect_right(beat_s, time_s) - 1, 0), beat_s.size - 2)
    a, b = float(beat_s[i]), float(beat_s[i + 1])
    pos = i + (time_s - a) / (b - a)
    frac = pos - math.floor(pos)
    if abs(frac - 0.5) < tol:
        return 0.5
    return 1.0 if frac < tol or frac > 1 - tol else 0.0


def lead_hand(kit: Kit) -> Limb:
    """The hand that keeps time and leads: the right one on a right-handed kit."""
    return Limb.RH if kit.handedness == "right" else Limb.LH


#: In an explicit-limb array: this note carries no annotation (the strategy decides).
UNANNOTATED = -2


def apply_explicit(routed: Routed, explicit: np.ndarray, kit: Kit) -> dict[int, str]:
    """Take a score's limbs as given before a strategy runs (see :mod:`.score`).

    A note marked left out is not played; a hi-hat note marked with a foot moves to the pedal;
    any other note marked with a foot is played by that foot, and a foot note marked with a
    hand is left to the hands (the strategy then keeps the marked hand). Returns the reasons.
    """
    reasons: dict[int, str] = {}
    for i in np.flatnonzero((explicit != UNANNOTATED) & (routed.piece >= 0)).tolist():
        want = int(explicit[i])
        if want == NOT_PLAYED:
            routed.hand[i] = False
            routed.limb[i] = NOT_PLAYED
            reasons[i] = "left out, as the score says"
        elif want in (LIMB_CODE[Limb.RF], LIMB_CODE[Limb.LF]):
            if routed.hand[i] and kit.pieces[int(routed.piece[i])].kind is PieceKind.HIHAT:
                routed.onsets["zone"][i] = _PEDAL_ZONE
                routed.onsets["hihat"][i] = _PEDAL_HIHAT
                reasons[i] = "hi-hat played with the pedal, as the score says"
            routed.hand[i] = False
            routed.limb[i] = want
        else:
            routed.hand[i] = True
    return reasons
