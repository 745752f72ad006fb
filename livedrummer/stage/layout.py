"""A stage's drummers as space on the floor: each kit's footprint, the gaps between them, the
camera that frames the group and the floor cells each drummer lights; pure numpy.

Why here and not in :mod:`.formation`: a formation is shapes and numbers; whether drummers fit
depends on their kits. A kit's *footprint* is the smallest circle, centred on its own bounding
box on the floor, that holds every piece and stand the renderer draws (the unit meshes of
:mod:`livedrummer.render.geometry` placed by :func:`~livedrummer.render.kitmesh.build_kit_mesh`,
at rest) and the seat; its diameter is what :func:`check_footprints` asks of two drummers'
footprint centres, so two kits never interpenetrate whatever their yaws. The rock5 kit's
footprint is 1.93 m.

The group camera (:func:`fit_group_camera`) keeps a stored camera's direction and field of
view and moves its target and distance until the projected corners of every drummer's box (its
footprint's bounding box, floor to head height) are centred in the frame and fill
:data:`FILL` of its width or height, whichever binds first: a fixed-point iteration on the
projected bounding box (a few steps; a step moves the target by the box's offset from the
centre at its depth and scales the distance by the box's size).

Floor cells: every drummer's floor disc lies on the same plane, so on a stage they would fight
for the pixels where discs overlap (the blocky black patches a 12-drummer arc showed, either
disc winning pixel by pixel, one lit by its spot and shadowed by its drummer, the other dark
at its rim). Each drummer's floor is drawn only over the points nearer to its own pool centre
than to any other's (a Voronoi cell, ``shaders/floor_cell.glsl``): :func:`cell_neighbours` gives
each drummer the other pool centres in its own frame. Limits: a drummer's shadow ends at its
cell's edge; the boxes are the kits at rest (a cymbal's swing may leave them by a few cm).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.render.camera import Camera
from livedrummer.render.geometry import all_meshes
from livedrummer.render.kitmesh import STAGE_RADIUS_M, build_kit_mesh

from .formation import Placement

FILL = 0.9  # share of the frame's width or height the group's boxes fill
HEAD_ABOVE_SEAT_M = 0.95  # the top of a seated drummer's head over the seat


@dataclass(frozen=True)
class Footprint:
    """A kit on the floor in its own frame (seat at the origin, facing +y): its box and circle."""

    lo: tuple[float, float, float]  # the box's low corner (x, y, z), m
    hi: tuple[float, float, float]

    @property
    def centre(self) -> tuple[float, float]:
        return ((self.lo[0] + self.hi[0]) / 2, (self.lo[1] + self.hi[1]) / 2)

    @property
    def diameter_m(self) -> float:
        """The footprint circle's diameter: the box's diagonal on the floor."""
        return math.hypot(self.hi[0] - self.lo[0], self.hi[1] - self.lo[1])

    def corners(self) -> np.ndarray:
        """The box's eight corners, (8, 3)."""
        lo, hi = np.asarray(self.lo), np.asarray(self.hi)
        pick = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], bool)
        out: np.ndarray = np.where(pick, hi, lo)
        return out


def footprint(kit: Kit) -> Footprint:
    """The kit's footprint (see the module docstring): every drawn part at rest, floor excluded,
    and a seated drummer's head."""
    mesh = build_kit_mesh(kit, floor=False)
    meshes = all_meshes()
    lo = np.array([0.0, 0.0, 0.0])
    hi = np.array([0.0, 0.0, kit.seat_height_m + HEAD_ABOVE_SEAT_M])
    for name in sorted(set(mesh.mesh)):
        rows = mesh.model[mesh.mesh == name]
        v = meshes[name].vertices[:, :3].astype(float)
        world = np.einsum("nij,vj->nvi", rows[:, :3, :3], v) + rows[:, None, :3, 3]
        lo = np.minimum(lo, world.reshape(-1, 3).min(axis=0))
        hi = np.maximum(hi, world.reshape(-1, 3).max(axis=0))
    lo[2] = 0.0
    return Footprint((float(lo[0]), float(lo[1]), 0.0), (float(hi[0]), float(hi[1]), float(hi[2])))


def to_world(placement: Placement, points: np.ndarray) -> np.ndarray:
    """Points (..., 2 or 3) in a drummer's frame turned by its yaw and moved to its spot."""
    a = math.radians(placement.yaw_deg)
    c, s = math.cos(a), math.sin(a)
    p = np.asarray(points, float)
    out = p.copy()
    out[..., 0] = c * p[..., 0] - s * p[..., 1] + placement.x
    out[..., 1] = s * p[..., 0] + c * p[..., 1] + placement.y
    return out


def to_local(placement: Placement, points: np.ndarray) -> np.ndarray:
    """The inverse of :func:`to_world`."""
    a = math.radians(placement.yaw_deg)
    c, s = math.cos(a), math.sin(a)
    p = np.asarray(points, float)
    x, y = p[..., 0] - placement.x, p[..., 1] - placement.y
    out = p.copy()
    out[..., 0] = c * x + s * y
    out[..., 1] = -s * x + c * y
    return out


def check_footprints(
    placements: Sequence[Placement], prints: Sequence[Footprint], labels: Sequence[str]
) -> None:
    """ValueError naming the first two drummers whose footprints overlap: their footprint
    centres closer than the larger footprint's diameter."""
    centres = [to_world(p, np.array(f.centre)) for p, f in zip(placements, prints, strict=True)]
    for i in range(len(centres)):
        for j in range(i + 1, len(centres)):
            gap = float(np.hypot(*(centres[i] - centres[j])))
            need = max(prints[i].diameter_m, prints[j].diameter_m)
            if gap < need - 1e-6:
                raise ValueError(
                    f"drummers {labels[i]} and {labels[j]} stand {gap:.2f} m apart; "
                    f"their kits need {need:.2f} m (one footprint): raise the "
                    "spacing or the radius, or move them"
                )


def group_points(placements: Sequence[Placement], prints: Sequence[Footprint]) -> np.ndarray:
    """Every drummer's box corners on the stage, (8 N, 3)."""
    return np.concatenate(
        [to_world(p, f.corners()) for p, f in zip(placements, prints, strict=True)]
    )


def fit_group_camera(base: Camera, points: np.ndarray, aspect: float, name: str) -> Camera:
    """``base``'s direction and field of view, moved to centre ``points`` and fill
    :data:`FILL` of the frame (see the module docstring)."""
    pts = np.asarray(points, float)
    offset = np.asarray(base.eye, float) - np.asarray(base.target, float)
    direction = offset / np.linalg.norm(offset)
    target = (pts.min(axis=0) + pts.max(axis=0)) / 2
    distance = float(np.linalg.norm(offset))
    tan_v = math.tan(math.radians(base.fov_deg) / 2)
    for _ in range(30):
        cam = Camera(name, _vec(target + direction * distance), _vec(target), base.fov_deg)
        view = cam.view()
        eye_space = pts @ view[:3, :3].T + view[:3, 3]
        depth = np.maximum(-eye_space[:, 2], 1e-3)
        x = eye_space[:, 0] / depth / (tan_v * aspect)  # -1..1 across the frame
        y = eye_space[:, 1] / depth / tan_v
        if np.any(eye_space[:, 2] > -0.05):  # points behind the eye: back off first
            distance *= 1.5
            continue
        mid_x, mid_y = (x.max() + x.min()) / 2, (y.max() + y.min()) / 2
        size = max((x.max() - x.min()) / 2, (y.max() - y.min()) / 2) / FILL
        right, up = view[0, :3], view[1, :3]
        at = float(np.linalg.norm(target - np.asarray(cam.eye)))
        shift = right * mid_x * tan_v * aspect * at + up * mid_y * tan_v * at
        target = target + shift
        distance *= size
        if abs(mid_x) < 1e-4 and abs(mid_y) < 1e-4 and abs(size - 1.0) < 1e-4:
            break
    return Camera(name, _vec(target + direction * distance), _vec(target), base.fov_deg)


def cell_neighbours(
    placements: Sequence[Placement], pool_centres: Sequence[np.ndarray]
) -> list[np.ndarray]:
    """Per drummer, the other drummers' pool centres (each given in its own drummer's frame)
    whose cells can cut its floor disc, in its own frame, (M, 2) float32."""
    world = [
        to_world(p, np.asarray(c, float)[:2]) for p, c in zip(placements, pool_centres, strict=True)
    ]
    out = []
    for k, p in enumerate(placements):
        near = [
            w
            for j, w in enumerate(world)
            if j != k and float(np.hypot(*(w - world[k]))) < 2 * STAGE_RADIUS_M
        ]
        local = to_local(p, np.array(near).reshape(-1, 2))
        out.append(local.astype(np.float32))
    return out


def _vec(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))
