"""Kit geometry to mesh instances: every shell, head, rim, cymbal, stand and pedal as a matrix.

The kit file says where each piece's playing surface is, which way it faces and how big it is
(:mod:`livedrummer.kit.model`); this module turns that into instances of the unit meshes of
:mod:`livedrummer.render.geometry`, so a mirrored or a user kit is drawn without code changes.
It is built once per kit (:func:`build_kit_mesh`); per frame, :meth:`KitMesh.instances` applies
the kit channels of :mod:`livedrummer.render.scene` (a cymbal's swing or a drum's shake about the
playing-surface centre, hi-hat lift along the surface normal, kick beater swing about its pivot,
footboards turned about their heel hinge, hit highlight) to all instances at once with array
operations. Which parts move how is read from :data:`livedrummer.kit.behaviour.BEHAVIOURS`.

An instance is one float32 row of ``INSTANCE_FLOATS``: the model matrix (16, column-major as
OpenGL reads it), colour (r, g, b, highlight) and material (metalness, shininess, kind,
logo flag), where kind is one of the ``MATERIAL_*`` codes the fragment shader branches on.
Limits: stands are straight poles with tripods under the piece (no boom arms, no tom mounts),
so a cymbal far from the floor gets a tall pole; pieces of kind cowbell, tambourine and
percussion are drawn as small drums.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from livedrummer.kit.behaviour import (
    BEHAVIOURS,
    FOOTBOARD_HINGE_M,
    FOOTBOARD_REST_RAD,
    HitMotion,
    PedalMotion,
)
from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.render.scene import (
    CH_HIGHLIGHT,
    CH_PEDAL,
    CH_TRAVEL,
    CH_WOBBLE,
    CH_WOBBLE_AZIMUTH,
    N_CHANNELS,
)

INSTANCE_FLOATS = 24
MATERIAL_PLAIN, MATERIAL_FLOOR, MATERIAL_CYMBAL, MATERIAL_HEAD, MATERIAL_SKIN = (
    0.0,
    1.0,
    2.0,
    3.0,
    4.0,
)
MOTION_STATIC, MOTION_WOBBLE, MOTION_LIFT, MOTION_BEATER, MOTION_PEDAL = 0, 1, 2, 3, 4

#: colour (sRGB-encoded rgb), metalness, shininess, material kind: lacquered shells are
#: dielectric with a sharp clear-coat highlight, chrome and stands metal, cymbals brass
LOOKS: dict[str, tuple[tuple[float, float, float], float, float, float]] = {
    "shell": ((0.62, 0.05, 0.07), 0.0, 140.0, MATERIAL_PLAIN),
    "snare_shell": ((0.72, 0.72, 0.76), 1.0, 80.0, MATERIAL_PLAIN),
    "head": ((0.70, 0.68, 0.62), 0.0, 18.0, MATERIAL_HEAD),
    "front_head": ((0.08, 0.08, 0.09), 0.0, 30.0, MATERIAL_HEAD),
    "chrome": ((0.80, 0.80, 0.84), 1.0, 90.0, MATERIAL_PLAIN),
    "stand": ((0.45, 0.45, 0.50), 1.0, 60.0, MATERIAL_PLAIN),
    "bronze": ((0.90, 0.66, 0.30), 1.0, 45.0, MATERIAL_CYMBAL),
    "felt": ((0.85, 0.85, 0.80), 0.0, 8.0, MATERIAL_PLAIN),
    "pedal": ((0.25, 0.25, 0.28), 1.0, 40.0, MATERIAL_PLAIN),
    "seat": ((0.05, 0.05, 0.05), 0.0, 12.0, MATERIAL_PLAIN),
    "floor": ((0.25, 0.18, 0.13), 0.0, 6.0, MATERIAL_FLOOR),
}

STAGE_RADIUS_M = 2.4
_Z = np.array([0.0, 0.0, 1.0])


def basis(z_axis: np.ndarray) -> np.ndarray:
    """A rotation (3x3, columns x y z) whose z column is ``z_axis`` (normalized)."""
    z = z_axis / np.linalg.norm(z_axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def placed(
    origin: np.ndarray, rotation: np.ndarray, scale: tuple[float, float, float]
) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = rotation * np.asarray(scale)[None, :]
    m[:3, 3] = origin
    return m


def segment(a: np.ndarray, b: np.ndarray, radius: float) -> np.ndarray:
    """Matrix that stretches the unit cylinder (z 0..1) from ``a`` to ``b``."""
    d = np.asarray(b, float) - np.asarray(a, float)
    return placed(np.asarray(a, float), basis(d), (radius, radius, float(np.linalg.norm(d))))


def rotations(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues rotation matrices (N, 3, 3) about unit ``axis`` (N, 3) by ``angle`` (N,)."""
    k = axis
    kx = np.zeros((len(k), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2] = -k[:, 2], k[:, 1]
    kx[:, 1, 0], kx[:, 1, 2] = k[:, 2], -k[:, 0]
    kx[:, 2, 0], kx[:, 2, 1] = -k[:, 1], k[:, 0]
    s = np.sin(angle)[:, None, None]
    c = np.cos(angle)[:, None, None]
    out: np.ndarray = np.eye(3)[None] + s * kx + (1.0 - c) * (kx @ kx)
    return out


@dataclass(frozen=True)
class KitMesh:
    """Static instance data of one kit, grouped by mesh name, and the per-frame update."""

    mesh: np.ndarray  # <U8 (N,), unit mesh name per instance
    model: np.ndarray  # float64 (N, 4, 4), rest placement
    color: np.ndarray  # float32 (N, 3)
    material: np.ndarray  # float32 (N, 4)
    highlight_weight: np.ndarray  # float32 (N,)
    piece: np.ndarray  # int32 (N,), -1 for the floor and the throne
    motion: np.ndarray  # int8 (N,), MOTION_*
    pivot: np.ndarray  # float64 (N, 3)
    axis: np.ndarray  # float64 (N, 3): lift direction or beater hinge axis
    pieces: int
    #: bool (N,): instances of the pieces whose hard hits surprise the face (crash, splash,
    #: china; :mod:`livedrummer.body.face`); empty: none
    crash: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def crash_like(self) -> np.ndarray:
        """bool (P,): per piece, whether it is crash-like (see ``crash``)."""
        out = np.zeros(self.pieces, dtype=bool)
        if self.crash.shape == self.piece.shape:
            hit = self.piece[self.crash]
            out[hit[hit >= 0]] = True
        return out

    @property
    def groups(self) -> dict[str, np.ndarray]:
        """Instance indices per mesh name, in a stable order."""
        return {name: np.flatnonzero(self.mesh == name) for name in sorted(set(self.mesh))}

    def instances(self, channels: np.ndarray) -> np.ndarray:
        """All instance rows (N, INSTANCE_FLOATS) float32 with ``channels`` (P, N_CHANNELS)
        applied."""
        n = len(self.mesh)
        ch = np.zeros((n, N_CHANNELS))
        has = self.piece >= 0
        ch[has] = channels[self.piece[has]]
        # Wobble: tilt about a horizontal axis through the playing-surface centre; beater and
        # footboard: turn about their hinge by the travel or pedal channel.
        az = ch[:, CH_WOBBLE_AZIMUTH]
        axis = np.stack([np.cos(az), np.sin(az), np.zeros(n)], axis=1)
        angle = np.where(self.motion == MOTION_WOBBLE, ch[:, CH_WOBBLE], 0.0)
        for kind, column in ((MOTION_BEATER, CH_TRAVEL), (MOTION_PEDAL, CH_PEDAL)):
            hinged = self.motion == kind
            axis[hinged] = self.axis[hinged]
            angle = np.where(hinged, ch[:, column], angle)
        rot = rotations(axis, angle)
        motion = np.tile(np.eye(4), (n, 1, 1))
        motion[:, :3, :3] = rot
        motion[:, :3, 3] = self.pivot - np.einsum("nij,nj->ni", rot, self.pivot)
        lift = self.motion == MOTION_LIFT
        motion[lift, :3, 3] += self.axis[lift] * ch[lift, CH_TRAVEL][:, None]
        model = motion @ self.model
        out = np.empty((n, INSTANCE_FLOATS), np.float32)
        out[:, :16] = model.transpose(0, 2, 1).reshape(n, 16)
        out[:, 16:19] = self.color
        out[:, 19] = np.clip(ch[:, CH_HIGHLIGHT], 0.0, 1.0) * self.highlight_weight
        out[:, 20:24] = self.material
        return out


@dataclass(frozen=True)
class _Move:
    """How an instance follows its piece's channels (see :meth:`KitMesh.instances`)."""

    piece: int
    motion: int
    pivot: np.ndarray
    axis: np.ndarray | None = None


class _Builder:
    def __init__(self) -> None:
        self.rows: list[tuple[str, np.ndarray, str, float, int, int, np.ndarray, np.ndarray]] = []

    def add(
        self,
        mesh: str,
        model: np.ndarray,
        look: str,
        *,
        highlight: float = 0.0,
        move: _Move | None = None,
    ) -> None:
        if move is None:
            move = _Move(-1, MOTION_STATIC, np.zeros(3))
        axis = np.zeros(3) if move.axis is None else move.axis
        self.rows.append((mesh, model, look, highlight, move.piece, move.motion, move.pivot, axis))

    def build(self, pieces: int) -> KitMesh:
        looks = [LOOKS[r[2]] for r in self.rows]
        return KitMesh(
            mesh=np.array([r[0] for r in self.rows]),
            model=np.array([r[1] for r in self.rows]),
            color=np.array([lk[0] for lk in looks], np.float32),
            material=np.array(
                [
                    (lk[1], lk[2], lk[3], float(r[2] == "front_head"))
                    for lk, r in zip(looks, self.rows, strict=True)
                ],
                np.float32,
            ),
            highlight_weight=np.array([r[3] for r in self.rows], np.float32),
            piece=np.array([r[4] for r in self.rows], np.int32),
            motion=np.array([r[5] for r in self.rows], np.int8),
            pivot=np.array([r[6] for r in self.rows], float),
            axis=np.array([r[7] for r in self.rows], float),
            pieces=pieces,
        )


def _stand(b: _Builder, top: np.ndarray, foot_xy: np.ndarray, look: str = "stand") -> None:
    base = np.array([foot_xy[0], foot_xy[1], 0.0])
    b.add("rod", segment(base, top, 0.011), look)
    knee = base + np.array([0.0, 0.0, min(0.32, 0.6 * max(float(top[2]), 0.05))])
    for k in range(3):
        ang = np.pi / 2 + k * 2 * np.pi / 3
        foot = base + 0.26 * np.array([np.cos(ang), np.sin(ang), 0.0])
        b.add("rod", segment(knee, foot, 0.008), look)


def _pedal(b: _Builder, pedal: np.ndarray, towards: np.ndarray, piece: int) -> None:
    """A footboard whose middle is under the ball of the foot (``pedal``), hinged at its heel
    end and turned up by the piece's pedal channel."""
    f = towards[:2] - pedal[:2]
    f = np.array([f[0], f[1], 0.0]) / max(float(np.hypot(*f)), 1e-9)
    x = np.cross(f, _Z)
    rot = np.stack([x, f, _Z], axis=1)
    tilt = rotations(x[None], np.array([FOOTBOARD_REST_RAD]))[0]
    centre = pedal + np.array([0.0, 0.0, 0.035])
    hinge = centre - FOOTBOARD_HINGE_M * (tilt @ f)
    board = _Move(piece, MOTION_PEDAL, hinge, x)
    b.add(
        "cube",
        placed(centre, tilt @ rot, (0.09, 2 * FOOTBOARD_HINGE_M, 0.015)),
        "pedal",
        move=board,
    )
    b.add("cube", placed(hinge - np.array([0.0, 0.0, 0.012]), rot, (0.11, 0.05, 0.02)), "pedal")


def _moves_when_hit(p: Piece) -> bool:
    return BEHAVIOURS[p.kind].hit is not HitMotion.NONE


def _drum(b: _Builder, p: Piece, i: int) -> None:
    c = np.asarray(p.position_m, float)
    n = p.normal
    rot = basis(n)
    bottom = c - n * p.depth_m
    wob = _Move(i, MOTION_WOBBLE if _moves_when_hit(p) else MOTION_STATIC, c)
    shell = "snare_shell" if p.kind is PieceKind.SNARE else "shell"
    b.add(
        "cylinder",
        placed(bottom, rot, (p.radius_m, p.radius_m, p.depth_m)),
        shell,
        highlight=0.3,
        move=wob,
    )
    b.add("disc", placed(c, rot, (p.radius_m, p.radius_m, 1.0)), "head", highlight=1.0, move=wob)
    for end in (c - n * 0.012, bottom - n * 0.004):
        b.add(
            "cylinder",
            placed(end, rot, (p.radius_m * 1.025, p.radius_m * 1.025, 0.018)),
            "chrome",
            move=wob,
        )
    if BEHAVIOURS[p.kind].pedal is PedalMotion.BEATER:
        flipped = rot * np.array([1.0, -1.0, -1.0])[None, :]
        b.add(
            "disc",
            placed(bottom, flipped, (p.radius_m, p.radius_m, 1.0)),
            "front_head",
            highlight=0.6,
            move=wob,
        )
        if p.pedal_position_m is not None:
            pedal = np.asarray(p.pedal_position_m, float)
            _pedal(b, pedal, c, i)
            contact = c - np.array([0.0, 0.0, 0.08]) + n * 0.03
            pivot = contact + n * 0.12
            pivot[2] = pedal[2] + 0.07
            hinge = np.cross(n, _Z)
            hinge /= np.linalg.norm(hinge)
            probe = rotations(hinge[None], np.array([0.1]))[0] @ (contact - pivot)
            if np.dot(probe - (contact - pivot), n) < 0:
                hinge = -hinge
            beat = _Move(i, MOTION_BEATER, pivot, hinge)
            b.add("rod", segment(pivot, contact, 0.005), "chrome", move=beat)
            b.add("sphere", placed(contact, np.eye(3), (0.03, 0.03, 0.03)), "felt", move=beat)
    else:
        _stand(b, bottom - n * 0.01, c[:2])


def _cymbal(b: _Builder, p: Piece, i: int) -> None:
    c = np.asarray(p.position_m, float)
    n = p.normal
    rot = basis(n)
    r = p.radius_m
    wob = _Move(i, MOTION_WOBBLE if _moves_when_hit(p) else MOTION_STATIC, c)
    if BEHAVIOURS[p.kind].pedal is PedalMotion.HIHAT:
        top = _Move(i, MOTION_LIFT, c, n)
        b.add("cymbal", placed(c - n * 0.05 * r, rot, (r, r, r)), "bronze", highlight=1.0, move=top)
        flipped = rot * np.array([1.0, -1.0, -1.0])[None, :]
        b.add("cymbal", placed(c - n * 0.02, flipped, (r, r, r)), "bronze", highlight=0.5)
        b.add("rod", segment(c, c + n * 0.22, 0.005), "chrome", move=top)
        _stand(b, c - n * 0.04, c[:2])
        if p.pedal_position_m is not None:
            _pedal(b, np.asarray(p.pedal_position_m, float), c, i)
    else:
        b.add("cymbal", placed(c - n * 0.05 * r, rot, (r, r, r)), "bronze", highlight=1.0, move=wob)
        b.add(
            "sphere", placed(c + n * 0.05 * r, np.eye(3), (0.012, 0.012, 0.012)), "felt", move=wob
        )
        _stand(b, c - n * 0.015, c[:2])


def build_kit_mesh(kit: Kit, *, floor: bool = True) -> KitMesh:
    """Instances for every piece of ``kit``, a throne at the seat height and the stage floor."""
    b = _Builder()
    if floor:
        centre = np.mean([p.position_m for p in kit.pieces], axis=0) if kit.pieces else np.zeros(3)
        b.add(
            "floor",
            placed(
                np.array([centre[0], centre[1] * 0.5, 0.0]),
                np.eye(3),
                (STAGE_RADIUS_M, STAGE_RADIUS_M, 1.0),
            ),
            "floor",
        )
    seat = kit.seat_height_m
    b.add(
        "cylinder", placed(np.array([0, -0.02, seat - 0.07]), np.eye(3), (0.17, 0.17, 0.07)), "seat"
    )
    b.add("disc", placed(np.array([0, -0.02, seat]), np.eye(3), (0.17, 0.17, 1.0)), "seat")
    _stand(b, np.array([0.0, -0.02, seat - 0.07]), np.array([0.0, -0.02]))
    for i, piece in enumerate(kit.pieces):
        if piece.kind.is_cymbal:
            _cymbal(b, piece, i)
        else:
            _drum(b, piece, i)
    from livedrummer.body.face import CRASH_KINDS

    crash = np.array([p.kind.value in CRASH_KINDS for p in kit.pieces] + [False], dtype=bool)
    built = b.build(len(kit.pieces))
    return replace(built, crash=crash[built.piece])  # piece -1 (floor, throne): the False


def empty_stage() -> KitMesh:
    """Only the stage floor (for tests: nothing may be drawn beyond it)."""
    b = _Builder()
    b.add("floor", placed(np.zeros(3), np.eye(3), (STAGE_RADIUS_M, STAGE_RADIUS_M, 1.0)), "floor")
    return b.build(0)
