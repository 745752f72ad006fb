"""The strike solve: a limb put onto the piece it hits, as joint rotations a pose can hold.

Why this module. Three callers need the same thing at a hit: the animation's contact keys
(:func:`~livedrummer.body.animation.animate`, one solve per hand note), its per-sample leg
chain (the feet follow their lift curves), and the live synth's quick contact (the body as
last sampled with one limb moved onto its piece, :func:`strike_poses`). They used to write
the target lookup, the IK call and the world-to-local chain out each on their own; here it is
written once:

* :func:`solve_strike` looks up the zone's target (point, normal, stick pitch; a hi-hat's
  point raised by its openness) and solves the arm onto it (:func:`~livedrummer.body.ik.solve_arm`);
* :func:`to_local` turns a chain of world rotations into local ones: each rotation relative
  to the one before it (the first relative to its parent's world rotation, or to the root
  frame), by :func:`~livedrummer.body.quat.relative`, the body's one world-to-local step;
* :func:`strike_poses` applies both to pose records, and sets the struck piece's channels as
  at a hit (full glow at the velocity; a cymbal's wobble, a beater or a footboard at zero);
* :func:`foot_contacts` solves every foot on every piece once: a foot's contact depends on
  nothing but the piece (the hip is fixed on the seat, the target is the footboard), so a
  caller on a hot path (the live synth's answer to a hit) looks it up instead of solving it
  again (:func:`strike_poses` ``feet=``); an arm's contact depends on the shoulder and chest
  of the record it is put into, so it stays a solve (one per limb and batch).

Limits: an arm keeps the shoulder position and chest rotation of the record it is given (the
torso is not re-solved); a foot's target is its piece's footboard (or the piece itself), with
no zone within it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body import quat
from livedrummer.body.ik import ArmSolution, LegSolution, solve_arm, solve_leg
from livedrummer.body.rig import Rig
from livedrummer.body.skeleton import ARM, LEG, J
from livedrummer.kit.vocabulary import ZONES, PieceKind, Zone

_PEDAL = ZONES.index(Zone.PEDAL)


def to_local(parent_q: np.ndarray | None, *chain: np.ndarray) -> list[np.ndarray]:
    """Local rotations of a chain of world rotations (each ``(N, 4)``, root to tip): the first
    relative to ``parent_q`` (its parent's world rotation; None: the root frame, unchanged),
    each next one relative to the one before it."""
    out: list[np.ndarray] = []
    prev = parent_q
    for q in chain:
        out.append(q if prev is None else quat.relative(prev, q))
        prev = q
    return out


def solve_strike(
    rig: Rig,
    limb: int,
    shoulder: np.ndarray,
    chest_q: np.ndarray,
    piece: np.ndarray,
    zone: np.ndarray,
    openness: np.ndarray,
) -> tuple[ArmSolution, np.ndarray, np.ndarray]:
    """Arm ``limb`` (0 right, 1 left) from ``shoulder`` (N, 3) with the chest at world
    rotation ``chest_q`` (N, 4) onto (``piece``, ``zone``) (N each; ``openness`` raises a
    hi-hat's point, NaN for none): the solution, the target points and their normals."""
    point, normal, pitch = rig.targets.lookup(piece, zone, openness)
    sign = 1.0 if limb == 0 else -1.0
    sol = solve_arm(rig.skeleton.lengths, shoulder, chest_q, sign, point, normal, pitch)
    return sol, point, normal


def leg_locals(leg: LegSolution) -> list[np.ndarray]:
    """Hip (in the root frame), knee and ankle local rotations of a leg solution."""
    return to_local(None, leg.hip_q, leg.knee_q, leg.ankle_q)


@dataclass(frozen=True)
class FootContacts:
    """Each foot's contact on each piece (:func:`foot_contacts`): index ``[foot, piece]``,
    foot 0 right, 1 left; local hip (root frame), knee and ankle rotations (..., 4) and the
    knee, ankle and toe positions (..., 3)."""

    hip_q: np.ndarray
    knee_q: np.ndarray
    ankle_q: np.ndarray
    knee: np.ndarray
    ankle: np.ndarray
    toe: np.ndarray


def foot_contacts(rig: Rig) -> FootContacts:
    """Both feet solved onto every piece's footboard (see the module docstring)."""
    skel, n = rig.skeleton, len(rig.kit.pieces)
    toe = np.array([footboard(rig, k) for k in range(n)]).reshape(n, 3)
    parts: list[list[np.ndarray]] = []
    for side in ("R", "L"):
        hip = np.broadcast_to(skel.root_m + skel.offsets[LEG[side][0]], (n, 3))
        leg = solve_leg(skel.lengths, hip, toe)
        parts.append([*leg_locals(leg), leg.knee, leg.ankle, leg.toe])
    return FootContacts(*(np.stack(arrays) for arrays in zip(*parts, strict=True)))


def strike_poses(
    rig: Rig,
    base: np.ndarray,
    limb: int,
    piece: np.ndarray,
    zone: np.ndarray,
    velocity: np.ndarray,
    openness: np.ndarray,
    feet: FootContacts | None = None,
) -> np.ndarray:
    """``base`` (N pose records) with ``limb`` (0-3: right hand, left hand, right foot, left
    foot) on (``piece``, ``zone``) at contact, each (a copy; see the module docstring);
    ``feet``: a foot's contact looked up there instead of solved (the same numbers)."""
    rec = base.copy()
    rot, pos = rec["rotation"], rec["position"]
    n = rec.size
    if limb in (0, 1):
        sh_j, el_j, wr_j, st_j, tip_j = ARM["R" if limb == 0 else "L"]
        chest_w = quat.mul(
            rot[:, J["lower_back"]].astype(np.float64), rot[:, J["chest"]].astype(np.float64)
        )
        shoulder = pos[:, sh_j].astype(np.float64)
        sol, _, _ = solve_strike(rig, limb, shoulder, chest_w, piece, zone, openness)
        locals_ = to_local(chest_w, sol.shoulder_q, sol.elbow_q, sol.wrist_q, sol.stick_q)
        for j, q in zip((sh_j, el_j, wr_j, st_j), locals_, strict=True):
            rot[:, j] = q
        for j, v in ((el_j, sol.elbow), (wr_j, sol.wrist), (st_j, sol.fulcrum), (tip_j, sol.tip)):
            pos[:, j] = v
    else:
        hip_j, knee_j, ankle_j, toe_j = LEG["R" if limb == 2 else "L"]
        if feet is not None:
            f, k = limb - 2, piece
            for j, q in ((hip_j, feet.hip_q), (knee_j, feet.knee_q), (ankle_j, feet.ankle_q)):
                rot[:, j] = q[f, k]
            for j, v in ((knee_j, feet.knee), (ankle_j, feet.ankle), (toe_j, feet.toe)):
                pos[:, j] = v[f, k]
            return _struck(rig, rec, limb, piece, zone, velocity)
        skel = rig.skeleton
        hip = np.broadcast_to(skel.root_m + skel.offsets[hip_j], (n, 3))
        toe = np.array([footboard(rig, int(k)) for k in piece.tolist()]).reshape(n, 3)
        leg = solve_leg(skel.lengths, hip, toe)
        for j, q in zip((hip_j, knee_j, ankle_j), leg_locals(leg), strict=True):
            rot[:, j] = q
        pos[:, knee_j], pos[:, ankle_j], pos[:, toe_j] = leg.knee, leg.ankle, leg.toe
    return _struck(rig, rec, limb, piece, zone, velocity)


def _struck(
    rig: Rig, rec: np.ndarray, limb: int, piece: np.ndarray, zone: np.ndarray, velocity: np.ndarray
) -> np.ndarray:
    """``rec`` with the struck pieces' channels as at a hit (in place; returned)."""
    kinds = [rig.kit.pieces[int(k)].kind for k in piece.tolist()]
    for k, (kind, pc, z, v) in enumerate(
        zip(kinds, piece.tolist(), zone.tolist(), velocity.tolist(), strict=True)
    ):
        pedal = limb >= 2 and kind in (PieceKind.KICK, PieceKind.HIHAT)
        if pedal or (kind.is_cymbal and kind is not PieceKind.HIHAT):
            rec["swing"][k, pc] = 0.0  # beater on the head, footboard down; wobble restarts
        if not (kind is PieceKind.HIHAT and z == _PEDAL):
            rec["glow"][k, pc] = v / 127.0
    return rec


def footboard(rig: Rig, piece: int) -> np.ndarray:
    """Where a foot playing ``piece`` puts the ball of the foot: its pedal, else the piece."""
    p = rig.kit.pieces[piece]
    return np.asarray(p.pedal_position_m or p.position_m, dtype=np.float64)
