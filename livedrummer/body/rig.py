"""A skeleton fitted to a kit: targets, surfaces, the torso's neutral pose, reach checks.

Built once per kit (:func:`build_rig`), before any performance: it is where a kit that the
drummer cannot play is refused. Every hand zone is tried with the limb the kit prefers for it
and every pedal with its foot, using the same IK the strokes use, with the torso in its
neutral (leaning, untwisted) pose; a miss raises :class:`~livedrummer.errors.UnreachableError`
naming piece, zone, limb and by how much it falls short. The other hand's reach is recorded
(``hand_ok``) so limb assignment can avoid impossible choices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body import fk, quat
from livedrummer.body.ik import solve_arm, solve_leg
from livedrummer.body.secondary import SecondaryParams
from livedrummer.body.skeleton import N_JOINTS, J, SegmentLengths, Skeleton, build_skeleton
from livedrummer.body.targets import Surfaces, TargetTable, surfaces, target_table
from livedrummer.errors import UnreachableError
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import ZONES, Limb, PieceKind, Zone

X = np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True)
class Rig:
    kit: Kit
    skeleton: Skeleton
    targets: TargetTable
    surfaces: Surfaces
    hand_ok: np.ndarray  # (2, P, Z) bool: right, left hand reaches (piece, zone)
    hand_gap_m: np.ndarray  # (2, P, Z) how far the tip falls short (0 when reached)


def neutral_world(
    skeleton: Skeleton, lean_deg: float, times: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations/positions of the neutral seated torso (arms at rest)."""
    local = quat.identity((times, N_JOINTS))
    lean = np.radians(lean_deg)
    local[:, J["lower_back"]] = quat.from_axis_angle(X, -lean)
    local[:, J["chest"]] = quat.from_axis_angle(X, lean * 0.3)
    root = np.broadcast_to(skeleton.root_m, (times, 3))
    return fk.forward(skeleton, local, root)


def build_rig(kit: Kit, lengths: SegmentLengths | None = None) -> Rig:
    skel = build_skeleton(lengths, kit.seat_height_m)
    table = target_table(kit)
    wq, wp = neutral_world(skel, SecondaryParams().lean_deg)
    chest = wq[0, J["chest"]]
    p, z = table.valid.shape
    ok = np.zeros((2, p, z), dtype=bool)
    gap = np.zeros((2, p, z))
    pieces = np.repeat(np.arange(p), z)
    zones = np.tile(np.arange(z), p)
    point, normal, pitch = table.lookup(pieces, zones)
    for k, (side, sign) in enumerate((("r", 1.0), ("l", -1.0))):
        shoulder = np.broadcast_to(wp[0, J[f"{side}_shoulder"]], point.shape)
        sol = solve_arm(
            skel.lengths,
            shoulder,
            np.broadcast_to(chest, (pieces.size, 4)),
            sign,
            point,
            normal,
            pitch,
        )
        miss = np.linalg.norm(sol.tip - point, axis=-1)
        ok[k] = (sol.reached & (miss < 1e-4)).reshape(p, z)
        gap[k] = miss.reshape(p, z)
    for i, piece in enumerate(kit.pieces):
        for zone in piece.zones:
            zi = ZONES.index(zone)
            if table.is_pedal[i, zi]:
                continue
            limb = piece.limb_for(zone)
            if not limb.is_hand:
                continue
            k = 0 if limb is Limb.RH else 1
            if not ok[k, i, zi]:
                raise UnreachableError(
                    f"{kit.source}: piece {piece.name!r} zone {zone.value} is out of reach of "
                    f"the {limb.value} stick by {gap[k, i, zi] * 1000:.0f} mm "
                    f"(target {np.round(table.point[i, zi], 3).tolist()} m)"
                )
        if piece.kind in (PieceKind.KICK, PieceKind.HIHAT) and piece.pedal_position_m:
            foot = piece.limb_for(Zone.PEDAL if piece.kind is PieceKind.HIHAT else Zone.HEAD)
            side = "r" if foot in (Limb.RF, Limb.RH) else "l"
            hip = wp[0, J[f"{side}_hip"]][None]
            toe = np.asarray(piece.pedal_position_m, dtype=np.float64)[None]
            leg = solve_leg(skel.lengths, hip, toe)
            if not leg.reached[0]:
                short = float(np.linalg.norm(leg.toe[0] - toe[0]))
                raise UnreachableError(
                    f"{kit.source}: pedal of {piece.name!r} at {list(piece.pedal_position_m)} m "
                    f"is out of reach of the {foot.value} foot by {short * 1000:.0f} mm"
                )
    return Rig(kit, skel, table, surfaces(kit), ok, gap)
