"""Eight stored viewpoints and smooth moves between them (SMED's view flags); pure numpy.

A :class:`Camera` is an eye, a target and a vertical field of view. The stored viewpoints are
placed relative to the kit (the centre of its pieces and the seat height), so they frame a
mirrored or a user kit without edits. The audience sits on the +y side of the kit (the drummer
faces it), so ``front`` is the front-of-house view. :class:`CameraMove` swings from one camera to
another over a duration: the target moves in a straight line while the eye travels around it
in spherical coordinates, so a move never passes through the kit.

Matrices follow OpenGL conventions (right-handed eye space looking down -z, clip depth -1..1)
and are returned row-major float32; the renderer transposes them for upload. Limits: no roll;
mouse orbit, zoom and pan make new cameras in :mod:`livedrummer.render.orbit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.kit.model import Kit


class CameraError(LivedrummerError):
    """An unknown camera name."""


@dataclass(frozen=True)
class Camera:
    name: str
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    fov_deg: float = 40.0

    def view(self) -> np.ndarray:
        return look_at(np.asarray(self.eye), np.asarray(self.target))

    def projection(self, aspect: float, near: float = 0.05, far: float = 30.0) -> np.ndarray:
        return perspective(self.fov_deg, aspect, near, far)

    def view_projection(self, aspect: float) -> np.ndarray:
        vp: np.ndarray = (self.projection(aspect) @ self.view()).astype(np.float32)
        return vp


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    forward = target - eye
    forward = forward / np.linalg.norm(forward)
    up = np.array([0.0, 0.0, 1.0])
    if abs(float(np.dot(forward, up))) > 0.99:  # looking straight down: audience at the top
        up = np.array([0.0, 1.0, 0.0])
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = right, true_up, -forward
    m[:3, 3] = -(m[:3, :3] @ eye)
    return m


def perspective(fov_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / math.tan(math.radians(fov_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


#: Stored viewpoint names, in the order the window's number keys 1..8 select them.
CAMERA_NAMES: tuple[str, ...] = (
    "stage", "front", "drummer", "overhead", "left", "right", "back", "kick",
)  # fmt: skip


def kit_cameras(kit: Kit) -> dict[str, Camera]:
    """The eight stored viewpoints, placed around ``kit``."""
    pts = np.array([p.position_m for p in kit.pieces]) if kit.pieces else np.zeros((1, 3))
    cx, cy = (float(v) for v in pts[:, :2].mean(axis=0))
    cz = 0.75
    c = np.array([cx, cy * 0.6, cz])
    head = (0.0, 0.23, kit.seat_height_m + 0.82)  # just in front of the face

    def cam(name: str, offset: tuple[float, float, float], fov: float = 40.0,
            drop: float = 0.0) -> Camera:  # fmt: skip
        at = c - (0.0, 0.0, drop)
        return Camera(name, tuple(float(v) for v in at + offset), tuple(float(v) for v in at), fov)  # type: ignore[arg-type]

    cams = [
        # front and stage frame the drummer and the kit to ~85 % of the frame's height
        cam("stage", (1.4, 2.4, 1.35), drop=0.12),
        cam("front", (0.0, 2.8, 0.62), drop=0.07),
        Camera("drummer", head, (cx, 0.75, 0.62), 70.0),
        cam("overhead", (0.0, 0.2, 3.6)),
        cam("left", (-3.2, 0.2, 0.45)),
        cam("right", (3.2, 0.2, 0.45)),
        cam("back", (0.0, -2.9, 1.2)),
        Camera("kick", (cx + 0.5, cy + 1.6, 0.32), (cx, cy * 0.5, 0.62), 55.0),
    ]
    return {c_.name: c_ for c_ in cams}


def pick_camera(kit: Kit, name: str) -> Camera:
    cams = kit_cameras(kit)
    if name not in cams:
        raise CameraError(f"unknown camera {name!r}; choose one of {', '.join(CAMERA_NAMES)}")
    return cams[name]


def _spherical(v: np.ndarray) -> np.ndarray:
    r = float(np.linalg.norm(v))
    return np.array([r, math.atan2(v[1], v[0]), math.asin(max(-1.0, min(1.0, v[2] / r)))])


def _smoothstep(x: float) -> float:
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x)


@dataclass(frozen=True)
class CameraMove:
    """A move from ``start`` to ``end`` beginning at ``t0_s`` and lasting ``duration_s``."""

    start: Camera
    end: Camera
    t0_s: float
    duration_s: float = 1.2

    def at(self, t_s: float) -> Camera:
        s = _smoothstep((t_s - self.t0_s) / self.duration_s) if self.duration_s > 0 else 1.0
        if s >= 1.0:
            return self.end
        if s <= 0.0:
            return self.start
        ta, tb = np.asarray(self.start.target), np.asarray(self.end.target)
        target = ta + s * (tb - ta)
        a = _spherical(np.asarray(self.start.eye) - ta)
        b = _spherical(np.asarray(self.end.eye) - tb)
        daz = (b[1] - a[1] + math.pi) % (2 * math.pi) - math.pi
        r, az, el = a[0] + s * (b[0] - a[0]), a[1] + s * daz, a[2] + s * (b[2] - a[2])
        eye = target + r * np.array(
            [math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]
        )
        fov = self.start.fov_deg + s * (self.end.fov_deg - self.start.fov_deg)
        return Camera(
            self.end.name,
            (float(eye[0]), float(eye[1]), float(eye[2])),
            (float(target[0]), float(target[1]), float(target[2])),
            fov,
        )
