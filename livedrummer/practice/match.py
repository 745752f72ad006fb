"""Matching a played take against its reference, note by note: one definition used everywhere.

The practice rig (the live readout, ``practice score`` on a recorded take, the reports) judges
with this module alone, so a live score and the score of the same take written to a file agree
by construction.

**What a piece is.** Two notes can match when they are on the same *piece*: the instrument a
note map gives the note (:data:`~livedrummer.kit.vocabulary.INSTRUMENTS`), whatever the zone
or articulation. A snare rim shot answers a snare head note and an open hi-hat answers a closed
one: the player struck the right thing at the right time, and which zone an e-kit reports
depends on the module and the player's angle more than on intent. The one exception is the
hi-hat *pedal* (zone ``pedal``): a foot chick is a different limb on a different control, so it
is its own piece, ``hihat_pedal``. Zones are kept per note for reports; they never decide a
match.

**The matching.** Per piece, each reference note is matched to at most one played note within
±window (default 100 ms). The matching is *monotone* (in time order: if reference a comes
before reference b, a's partner comes before b's), and among monotone matchings it has the most
pairs and, among those, the least total |offset|: a dynamic programme over (reference, played)
prefixes. Only pairs within the window can match, so each reference row of the table is only
computed over its band of candidates (found by binary search); outside its band a row is a copy
of the one before or constant, which keeps the cost to O(n + m + candidate pairs) and the
trace-back exact. Offsets enter the objective as integer microseconds, so ties are exact and
the result does not depend on floating-point order.

A greedy nearest-first pass is not good enough: with two snare notes 60 ms apart and one hit
between them, greedy may give the hit to the first and leave a later, better-placed hit
stranded; the programme maximises the count first.

**Then, in order:** a reference note left unmatched is a *wrong piece* when an unmatched played
note of *another* piece lies within the window (the same programme, over the leftovers, with
"different piece" as the condition; that played note is used up by it); otherwise it is
*missed*. Played notes left after both steps are *extra*. With ``pieces`` given (judge only
these), reference notes of other pieces are not judged, and played notes of other pieces may
still make a wrong piece but are never counted as extra.

Offsets are ``played - reference`` in milliseconds (positive = late); the velocity difference
is ``played - reference``. Limits: the matching never looks at velocity or zone; a take whose
tempo drifts by more than the window against the reference is judged as played (use the
reference's tempo for the take).
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from livedrummer.kit.vocabulary import INSTRUMENTS, ZONES, Zone

DEFAULT_WINDOW_MS = 100.0

#: Piece names in code order: the instruments, then the hi-hat pedal (see the module docstring).
HIHAT_PEDAL = "hihat_pedal"
PIECES: tuple[str, ...] = (*INSTRUMENTS, HIHAT_PEDAL)
PIECE_CODE: dict[str, int] = {name: i for i, name in enumerate(PIECES)}
_PEDAL_ZONE = ZONES.index(Zone.PEDAL)
_HIHAT = INSTRUMENTS.index("hihat")


class Result(IntEnum):
    """What became of a reference note; the order is the JSON names' order."""

    HIT = 0
    WRONG_PIECE = 1
    MISSED = 2


RESULT_NAMES: tuple[str, ...] = ("hit", "wrong_piece", "missed")

NOTE_DTYPE = np.dtype(
    [
        ("ref", "<i4"),  # index of the note in the reference given (before ``pieces``)
        ("time_s", "<f8"),  # reference time
        ("piece", "u1"),  # index into PIECES
        ("velocity", "u1"),  # reference velocity
        ("result", "u1"),  # Result
        ("played", "<i4"),  # index of the played note it took (hit or wrong piece), else -1
        ("offset_ms", "<f8"),  # played - reference (NaN when missed)
        ("velocity_diff", "<i2"),  # played - reference (0 when missed)
    ]
)


def piece_codes(onsets: np.ndarray) -> np.ndarray:
    """The piece (index into :data:`PIECES`) of each onset (ONSET_DTYPE)."""
    inst = onsets["instrument"].astype(np.int16)
    pedal = (inst == _HIHAT) & (onsets["zone"] == _PEDAL_ZONE)
    return np.where(pedal, PIECE_CODE[HIHAT_PEDAL], inst).astype(np.uint8)


def parse_pieces(spec: str) -> frozenset[int]:
    """``snare,hihat`` as piece codes; ValueError naming an unknown piece."""
    out = set()
    for word in (w.strip() for w in spec.split(",")):
        if word not in PIECE_CODE:
            raise ValueError(f"unknown piece {word!r} (pieces: {', '.join(PIECES)})")
        out.add(PIECE_CODE[word])
    if not out:
        raise ValueError("no pieces named")
    return frozenset(out)


def monotone_match(
    ref_s: np.ndarray,
    played_s: np.ndarray,
    window_s: float,
    allowed: Callable[[int, int], bool] | None = None,
) -> list[tuple[int, int]]:
    """The monotone matching of two sorted time lists within ±``window_s``: most pairs, then
    least total |offset| (see the module docstring). Returns (ref index, played index) pairs in
    time order. ``allowed(i, j)`` may forbid a pair within the window."""
    n, m = int(ref_s.size), int(played_s.size)
    if n == 0 or m == 0:
        return []
    lo = np.searchsorted(played_s, ref_s - window_s, side="left")
    hi = np.searchsorted(played_s, ref_s + window_s, side="right")
    # Integer objective: pairs * big - total |offset| in µs (exact ties, no float drift).
    window_us = int(np.ceil(window_s * 1e6)) + 1
    big = window_us * (n + 1)
    row = np.zeros(m + 1, dtype=np.int64)  # row[j] = best over the refs so far, played[:j]
    filled = 0  # row[filled + 1:] may be stale and equals row[filled]
    choices: list[np.ndarray] = []  # per ref: 0 up (skip ref), 1 left (skip played), 2 match
    for i in range(n):
        a, b = int(lo[i]), int(hi[i])
        if b > filled:
            row[filled + 1 : b + 1] = row[filled]
            filled = b
        if b <= a:
            choices.append(np.zeros(0, dtype=np.int8))
            continue
        old = row[a : b + 1].copy()  # F_i(j) for j in [a, b]
        choice = np.zeros(b - a, dtype=np.int8)
        for k, j in enumerate(range(a + 1, b + 1)):
            best = int(old[k + 1])  # up: ref i unmatched
            pick = 0
            left = int(row[j - 1])
            if left > best:
                best, pick = left, 1
            if allowed is None or allowed(i, j - 1):
                off_us = round(abs(float(played_s[j - 1] - ref_s[i])) * 1e6)
                diag = int(old[k]) + big - off_us
                if diag > best:
                    best, pick = diag, 2
            row[j] = best
            choice[k] = pick
        choices.append(choice)
    pairs: list[tuple[int, int]] = []
    i, j = n, m
    while i > 0 and j > 0:
        r = i - 1
        a, b = int(lo[r]), int(hi[r])
        if j > b:
            j = b
        elif j <= a:
            i -= 1
        else:
            pick = int(choices[r][j - a - 1])
            if pick == 0:
                i -= 1
            elif pick == 1:
                j -= 1
            else:
                pairs.append((r, j - 1))
                i, j = i - 1, j - 1
    pairs.reverse()
    return pairs


@dataclass(frozen=True)
class Matching:
    """The judgement of one take: one row per judged reference note, and the extra notes.

    ``notes`` (NOTE_DTYPE) in reference time order; ``played_piece``/``played_s`` describe the
    played notes (indices in ``notes["played"]`` and ``extra`` point into them).
    """

    notes: np.ndarray
    extra: np.ndarray  # int, indices of played notes counted as extra
    played_s: np.ndarray
    played_piece: np.ndarray
    window_ms: float


def match_take(
    ref: np.ndarray,
    played: np.ndarray,
    window_ms: float = DEFAULT_WINDOW_MS,
    pieces: Collection[int] | None = None,
) -> Matching:
    """Judge ``played`` against ``ref`` (both ONSET_DTYPE, sorted by time) as the module
    docstring defines; ``pieces``: judge only these piece codes (None: all)."""
    if not window_ms > 0:
        raise ValueError(f"window {window_ms} ms: must be > 0")
    window_s = window_ms / 1e3
    ref_piece = piece_codes(ref)
    judged = np.ones(ref.size, dtype=bool) if pieces is None else np.isin(ref_piece, list(pieces))
    ref_index = np.flatnonzero(judged)
    ref = ref[judged]
    ref_piece = ref_piece[judged]
    play_piece = piece_codes(played)
    ref_t = ref["time_s"].astype(np.float64)
    play_t = played["time_s"].astype(np.float64)
    notes = np.zeros(ref.size, dtype=NOTE_DTYPE)
    notes["ref"] = ref_index
    notes["time_s"] = ref_t
    notes["piece"] = ref_piece
    notes["velocity"] = ref["velocity"]
    notes["result"] = Result.MISSED
    notes["played"] = -1
    notes["offset_ms"] = np.nan
    used = np.zeros(played.size, dtype=bool)
    for code in np.unique(ref_piece):
        ri = np.flatnonzero(ref_piece == code)
        pj = np.flatnonzero(play_piece == code)
        for a, b in monotone_match(ref_t[ri], play_t[pj], window_s):
            _take(notes, int(ri[a]), int(pj[b]), Result.HIT, ref, played)
            used[pj[b]] = True
    left_r = np.flatnonzero(notes["result"] == Result.MISSED)
    left_p = np.flatnonzero(~used)
    rp, pp = ref_piece[left_r], play_piece[left_p]

    def other_piece(a: int, b: int) -> bool:
        return bool(rp[a] != pp[b])

    for a, b in monotone_match(ref_t[left_r], play_t[left_p], window_s, other_piece):
        _take(notes, int(left_r[a]), int(left_p[b]), Result.WRONG_PIECE, ref, played)
        used[left_p[b]] = True
    counted = np.ones(played.size, dtype=bool)
    if pieces is not None:
        counted = np.isin(play_piece, list(pieces))
    extra = np.flatnonzero(~used & counted)
    return Matching(notes, extra, play_t, play_piece, float(window_ms))


def _take(
    notes: np.ndarray, i: int, j: int, result: Result, ref: np.ndarray, played: np.ndarray
) -> None:
    notes["result"][i] = result
    notes["played"][i] = j
    notes["offset_ms"][i] = (float(played["time_s"][j]) - float(ref["time_s"][i])) * 1e3
    notes["velocity_diff"][i] = int(played["velocity"][j]) - int(ref["velocity"][i])
