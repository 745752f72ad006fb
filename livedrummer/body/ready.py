"""The waiting hand: between its strokes a hand hovers in a ready pose above its last piece.

Why. Left to the stroke keys alone, a hand with a rest of a beat or more eases from one
stroke's rebound to the next one's preparation in the contact pose's own frame: for the snare
hand that is the wrist low by the hip, the stick pointing away from the audience, a stub seen
from the front. A drummer's waiting hand is up, over the drum, stick raised: ready. Here a
gap of at least :attr:`ReadyParams.min_gap_s` between two notes of a hand gets two *ready*
keys, ``settle_s`` after the first note's rebound and ``lead_s`` before the second note's
preparation; both hold the ready pose above the piece the hand **last** played (the IK target
raised ``height_m`` above that zone, the wrist cocked by ``lift``), and the stroke that
follows travels from there. The first note gets one ready key before it (above its own
piece); after the last note the hand settles into the ready pose and stays.

Above the *last* piece, not the next, because it is causal: the live synth cannot know a
note before it arrives (it shows the body only ``D`` behind the sound), so a wait that
anticipated the next piece would be drawn offline and never live; this way the two twins
draw the same wait and differ, as before, only inside the next note's preparation.

A ready key is of kind :data:`~livedrummer.body.strokes.TRAVEL` (the clearance search raises
or lowers it like any arc between pieces) and points at a *virtual note* ``n + r``: the
animation appends the ready poses after the notes' contact poses, so the key machinery needs
no new case. Limits: the ready height is one figure for every piece (a crash waits as high
above its bow as a snare above its head); the hand waits over one piece, not between two.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body.ik import ArmSolution, solve_arm
from livedrummer.body.rig import Rig
from livedrummer.body.strokes import AFTER, BEFORE, TRAVEL, Keys


@dataclass(frozen=True, slots=True)
class ReadyParams:
    min_gap_s: float = 0.45  # a hand rests at least this long between notes to wait ready
    settle_s: float = 0.10  # after the rebound key, the ready pose is reached this much later
    lead_s: float = 0.10  # and left this long before the next preparation key
    height_m: float = 0.14  # the ready pose's stick tip above the zone's contact point
    lift: float = 0.25  # the wrist's cock in the ready pose, as a stroke's lift λ
    enabled: bool = True  # False: no ready keys (the strokes' own keys only)


@dataclass(frozen=True)
class ReadyKeys:
    """A hand's keys with the ready keys inserted, and what each ready key waits above."""

    keys: Keys
    time_s: np.ndarray  # (R,) the ready keys' times
    note: np.ndarray  # (R,) the note whose piece and zone each waits above


def ready_keys(keys: Keys, note_s: np.ndarray, params: ReadyParams) -> ReadyKeys:
    """``keys`` of a hand's notes (at ``note_s``, sorted) with ready keys inserted (see the
    module docstring); the ready key ``r`` has note and note2 ``n + r``."""
    n = note_s.size
    if n == 0 or not params.enabled:
        return ReadyKeys(keys, np.zeros(0), np.zeros(0, np.int64))
    after = _key_time(keys, AFTER, n, note_s)
    before = _key_time(keys, BEFORE, n, note_s)
    gap = np.diff(note_s)
    wait = np.flatnonzero(gap >= params.min_gap_s)
    a = after[wait] + params.settle_s
    b = before[wait + 1] - params.lead_s
    ok = b > a + 1e-3
    wait, a, b = wait[ok], a[ok], b[ok]
    times = [before[:1] - params.lead_s, a, b, after[-1:] + params.settle_s]
    of = [np.zeros(1, np.int64), wait, wait, np.full(1, n - 1, np.int64)]
    r_t = np.concatenate(times)
    r_note = np.concatenate(of).astype(np.int64)
    # a travel arc inside a gap that now waits ready is the ready keys' to make
    inside = np.zeros(keys.time_s.size, dtype=bool)
    for lo, hi in zip(a, b, strict=True):
        inside |= (
            (keys.kind == TRAVEL)
            & (keys.time_s > lo - params.settle_s)
            & (keys.time_s < hi + params.lead_s)
        )
    keep = ~inside
    virtual = n + np.arange(r_t.size)
    t = np.concatenate([keys.time_s[keep], r_t])
    order = np.argsort(t, kind="stable")
    joined = Keys(
        t[order],
        np.concatenate([keys.lift[keep], np.full(r_t.size, params.lift)])[order],
        np.concatenate([keys.kind[keep], np.full(r_t.size, TRAVEL)])[order],
        np.concatenate([keys.note[keep], virtual])[order],
        np.concatenate([keys.note2[keep], virtual])[order],
        np.concatenate([keys.anchor_s[keep], r_t])[order],
    )
    return ReadyKeys(joined, r_t, r_note)


def _key_time(keys: Keys, kind: int, n: int, note_s: np.ndarray) -> np.ndarray:
    """Per note, the time of its ``kind`` key (its contact time where it has none: merged)."""
    out = note_s.astype(np.float64).copy()
    mine = np.flatnonzero(keys.kind == kind)
    out[keys.note[mine]] = keys.time_s[mine]
    return out


def waiting(note_s: np.ndarray, params: ReadyParams) -> np.ndarray:
    """Per gap between consecutive notes: True where the hand waits ready in it."""
    return np.diff(note_s) >= params.min_gap_s


def solve_ready(
    rig: Rig,
    limb: int,
    shoulder: np.ndarray,
    chest_q: np.ndarray,
    piece: np.ndarray,
    zone: np.ndarray,
    openness: np.ndarray,
    height_m: float,
) -> tuple[ArmSolution, np.ndarray, np.ndarray]:
    """Arm ``limb`` (0 right, 1 left) in the ready pose over (``piece``, ``zone``): the stick
    as at contact, its tip ``height_m`` straight above the contact point (the solution, the
    raised points and the zones' normals)."""
    point, normal, pitch = rig.targets.lookup(piece, zone, openness)
    raised = point + np.array([0.0, 0.0, height_m])
    sign = 1.0 if limb == 0 else -1.0
    sol = solve_arm(rig.skeleton.lengths, shoulder, chest_q, sign, raised, normal, pitch)
    return sol, raised, normal
