"""Where on each piece a stick (or foot) lands, derived from the kit geometry alone.

Every (piece, zone) gets a target point on the playing surface, the surface normal there, a
preferred stick pitch (how steeply the stick meets the surface) and the in-plane direction
towards the drummer. Drums: the head zone is the centre of the head, a rim shot lands on the
edge nearest the drummer, a cross-stick lies almost flat with its tip on the head between
centre and near edge (the butt end on the far rim is not modelled).
Cymbals: bell, bow and edge lie at fixed fractions of the radius on the drummer's side. Kick
head: the beater's contact point below the head centre; pedal zones: the footboard. No
per-kit hand-set pose is needed, so a mirrored or user kit works unchanged.

The hi-hat's top cymbal rises with its openness (:data:`HIHAT_MAX_LIFT_M` when fully open),
so its bow and edge targets move along the normal with the onset's openness.

:class:`Surfaces` packs every piece's playing disc (centre, normal, radius, slab depth) as
arrays for the penetration check. Limits: surfaces are flat discs (no cymbal cone, no rim
height); pieces are not tested against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import PieceKind, Zone

HIHAT_MAX_LIFT_M = 0.03
KICK_BEATER_DROP = 0.35  # beater contact below the kick head centre, in radii

#: Fraction of the radius (towards the drummer; negative = away) and stick pitch (degrees
#: below the surface plane) per zone.
ZONE_PLACE: dict[Zone, tuple[float, float]] = {
    Zone.HEAD: (0.0, 12.0),
    Zone.RIM: (0.97, 4.0),
    Zone.CROSS_STICK: (0.45, 2.0),
    Zone.BOW: (0.6, 10.0),
    Zone.EDGE: (0.95, 4.0),
    Zone.BELL: (0.15, 22.0),
    Zone.PEDAL: (0.0, 0.0),
}
CYMBAL_SLAB_M = 0.015  # how far below a cymbal's surface still counts as inside it


def towards_drummer(piece: Piece) -> np.ndarray:
    """Unit vector in the piece's surface plane pointing towards the seat."""
    n = piece.normal
    c = np.asarray(piece.position_m, dtype=np.float64)
    to_seat = np.array([-c[0], -c[1], 0.0])
    v = to_seat - np.dot(to_seat, n) * n
    norm = float(np.linalg.norm(v))
    if norm < 1e-9:  # a surface facing the seat squarely: take "down" in its plane
        v = np.array([0.0, 0.0, -1.0]) - n[2] * n
        norm = float(np.linalg.norm(v))
    out: np.ndarray = v / norm
    return out


@dataclass(frozen=True)
class Target:
    point: np.ndarray  # (3,) on the surface
    normal: np.ndarray  # (3,) unit, into the air
    pitch_rad: float  # stick angle below the surface plane at contact
    is_pedal: bool


def zone_target(piece: Piece, zone: Zone) -> Target:
    """The contact point of ``zone`` on ``piece`` with the hi-hat closed."""
    n = piece.normal
    c = np.asarray(piece.position_m, dtype=np.float64)
    if zone is Zone.PEDAL or (piece.kind is PieceKind.KICK and zone is Zone.HEAD):
        if piece.kind is PieceKind.KICK and zone is Zone.HEAD:
            point = c + np.array([0.0, 0.0, -KICK_BEATER_DROP * piece.radius_m])
            return Target(point, n, 0.0, True)
        pedal = piece.pedal_position_m if piece.pedal_position_m is not None else piece.position_m
        return Target(np.asarray(pedal, dtype=np.float64), np.array([0.0, 0.0, 1.0]), 0.0, True)
    frac, pitch = ZONE_PLACE[zone]
    point = c + frac * piece.radius_m * towards_drummer(piece)
    return Target(point, n, float(np.radians(pitch)), False)


@dataclass(frozen=True)
class TargetTable:
    """Target per (piece index, zone code), as arrays for vectorized lookups."""

    point: np.ndarray  # (P, Z, 3)
    normal: np.ndarray  # (P, Z, 3)
    pitch_rad: np.ndarray  # (P, Z)
    is_pedal: np.ndarray  # (P, Z) bool
    valid: np.ndarray  # (P, Z) bool: the piece offers this zone
    hihat_lift_dir: np.ndarray  # (P, 3): normal for the hi-hat, zero elsewhere

    def lookup(
        self, piece: np.ndarray, zone: np.ndarray, openness: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points, normals and stick pitches for arrays of piece indices and zone codes."""
        point = self.point[piece, zone]
        if openness is not None:
            lift = np.nan_to_num(np.asarray(openness, dtype=np.float64), nan=0.0)
            point = point + (HIHAT_MAX_LIFT_M * np.clip(lift, 0.0, 1.0))[:, None] * (
                self.hihat_lift_dir[piece] * ~self.is_pedal[piece, zone][:, None]
            )
        return point, self.normal[piece, zone], self.pitch_rad[piece, zone]


def target_table(kit: Kit) -> TargetTable:
    from livedrummer.kit.vocabulary import ZONES

    p, z = len(kit.pieces), len(ZONES)
    point = np.zeros((p, z, 3))
    normal = np.zeros((p, z, 3))
    normal[..., 2] = 1.0
    pitch = np.zeros((p, z))
    pedal = np.zeros((p, z), dtype=bool)
    valid = np.zeros((p, z), dtype=bool)
    lift = np.zeros((p, 3))
    for i, piece in enumerate(kit.pieces):
        zones = set(piece.zones)
        if piece.kind is PieceKind.HIHAT:
            zones.add(Zone.PEDAL)
            lift[i] = piece.normal
        for k, zone in enumerate(ZONES):
            # a zone the piece lacks falls back to its first zone, so lookups never fail
            use = zone if zone in zones else piece.zones[0]
            t = zone_target(piece, use)
            point[i, k], normal[i, k], pitch[i, k], pedal[i, k] = (
                t.point,
                t.normal,
                t.pitch_rad,
                t.is_pedal,
            )
            valid[i, k] = zone in zones
    return TargetTable(point, normal, pitch, pedal, valid, lift)


@dataclass(frozen=True)
class Surfaces:
    """Every piece's playing disc, for penetration tests."""

    centre: np.ndarray  # (P, 3)
    normal: np.ndarray  # (P, 3)
    radius: np.ndarray  # (P,)
    slab: np.ndarray  # (P,) depth below the surface that counts as inside


def surfaces(kit: Kit) -> Surfaces:
    centre = np.array([p.position_m for p in kit.pieces], dtype=np.float64)
    normal = np.array([p.normal for p in kit.pieces])
    radius = np.array([p.radius_m for p in kit.pieces])
    slab = np.array(
        [CYMBAL_SLAB_M if p.kind.is_cymbal else max(p.depth_m, CYMBAL_SLAB_M) for p in kit.pieces]
    )
    return Surfaces(centre, normal, radius, slab)


def penetration_depth(s: Surfaces, points: np.ndarray) -> np.ndarray:
    """Depth (m, >= 0) of each point (..., 3) below the deepest surface it is inside."""
    rel = points[..., None, :] - s.centre  # (..., P, 3)
    h = np.sum(rel * s.normal, axis=-1)  # height above each surface
    radial = np.linalg.norm(rel - h[..., None] * s.normal, axis=-1)
    inside = (radial <= s.radius) & (h < 0.0) & (h > -s.slab)
    out: np.ndarray = np.max(np.where(inside, -h, 0.0), axis=-1)
    return out
