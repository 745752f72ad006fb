"""Mouse orbit, zoom and pan of a camera, and the user's eight stored viewpoints; pure.

A window turns mouse input into new :class:`~livedrummer.render.camera.Camera` s with these
functions and knows nothing of the maths: dragging with the left button orbits the eye about
the target (:func:`orbit`: a drag across the whole window height turns it by
:data:`ORBIT_RAD_PER_HEIGHT`, the elevation clamped short of the poles, where the view's up
would flip), the wheel zooms (:func:`zoom`: the eye moves towards the target by a factor per
notch, within :data:`MIN_DISTANCE_M`..:data:`MAX_DISTANCE_M`), and dragging with the right or
middle button pans (:func:`pan`: eye and target slide together in the view plane so the point
under the cursor stays under it at the target's depth).

A :class:`Viewpoints` store holds up to eight user cameras (Shift+1..8 stores, 1..8 recalls
a stored one before the built-in camera of that number), saved as JSON in the user's home
(:func:`livedrummer.resources.user_home`, ``viewpoints.json``) so they survive a restart. A
file that cannot be read is reported by :class:`ViewpointError` naming the file and the
field; the window logs it and starts with no stored viewpoints. Limits: no roll; one store per
user, not per kit (the cameras are in kit coordinates, so they fit kits of similar size).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.render.camera import Camera

ORBIT_RAD_PER_HEIGHT = math.pi  # a drag of the window's height turns the view half round
MAX_ELEVATION_RAD = math.radians(85.0)
ZOOM_PER_NOTCH = 0.9  # the eye's distance is multiplied by this per wheel notch towards
MIN_DISTANCE_M = 0.3
MAX_DISTANCE_M = 20.0
SLOTS = 8
FILE_NAME = "viewpoints.json"
_Z = np.array([0.0, 0.0, 1.0])


class ViewpointError(LivedrummerError):
    """A viewpoints file that is not the JSON this module writes."""


def _camera(like: Camera, eye: np.ndarray, target: np.ndarray) -> Camera:
    e = (float(eye[0]), float(eye[1]), float(eye[2]))
    t = (float(target[0]), float(target[1]), float(target[2]))
    return Camera(like.name, e, t, like.fov_deg)


def orbit(cam: Camera, dx_px: float, dy_px: float, height_px: int) -> Camera:
    """``cam`` with its eye turned about the target by a drag of (dx, dy) pixels (x right,
    y down): the scene turns with the cursor (a drag to the right swings the eye to its own
    left), and a drag down raises the eye."""
    target = np.asarray(cam.target, np.float64)
    rel = np.asarray(cam.eye, np.float64) - target
    r = float(np.linalg.norm(rel))
    azimuth = math.atan2(rel[1], rel[0]) - ORBIT_RAD_PER_HEIGHT * dx_px / max(height_px, 1)
    elevation = math.asin(max(-1.0, min(1.0, rel[2] / r)))
    elevation += ORBIT_RAD_PER_HEIGHT * dy_px / max(height_px, 1)
    elevation = max(-MAX_ELEVATION_RAD, min(MAX_ELEVATION_RAD, elevation))
    direction = np.array(
        [
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        ]
    )
    return _camera(cam, target + r * direction, target)


def zoom(cam: Camera, notches: float) -> Camera:
    """``cam`` with its eye ``notches`` wheel notches nearer the target (negative: further)."""
    target = np.asarray(cam.target, np.float64)
    rel = np.asarray(cam.eye, np.float64) - target
    r = float(np.linalg.norm(rel))
    new_r = min(MAX_DISTANCE_M, max(MIN_DISTANCE_M, r * ZOOM_PER_NOTCH**notches))
    return _camera(cam, target + rel * (new_r / r), target)


def pan(cam: Camera, dx_px: float, dy_px: float, height_px: int) -> Camera:
    """``cam`` slid in its view plane by a drag of (dx, dy) pixels: what was under the cursor
    at the target's depth follows it."""
    eye = np.asarray(cam.eye, np.float64)
    target = np.asarray(cam.target, np.float64)
    view = cam.view()
    right, up = view[0, :3], view[1, :3]
    r = float(np.linalg.norm(target - eye))
    metres_per_px = 2.0 * r * math.tan(math.radians(cam.fov_deg) / 2.0) / max(height_px, 1)
    shift = (-dx_px * right + dy_px * up) * metres_per_px
    return _camera(cam, eye + shift, target + shift)


@dataclass
class Viewpoints:
    """Up to :data:`SLOTS` stored cameras, slot 1..8 (see the module docstring)."""

    slots: dict[int, Camera] = field(default_factory=dict)

    def store(self, slot: int, cam: Camera) -> None:
        _check_slot(slot)
        self.slots[slot] = Camera(f"view {slot}", cam.eye, cam.target, cam.fov_deg)

    def recall(self, slot: int) -> Camera | None:
        _check_slot(slot)
        return self.slots.get(slot)

    def to_json(self) -> str:
        rows = {
            str(k): {"eye": list(c.eye), "target": list(c.target), "fov_deg": c.fov_deg}
            for k, c in sorted(self.slots.items())
        }
        return json.dumps({"version": 1, "viewpoints": rows}, indent=1) + "\n"

    @classmethod
    def from_json(cls, text: str, source: str) -> Viewpoints:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ViewpointError(f"{source}: not JSON ({exc.msg}, line {exc.lineno})") from None
        if not isinstance(data, dict) or data.get("version") != 1:
            raise ViewpointError(f"{source}: field 'version' must be 1")
        rows = data.get("viewpoints")
        if not isinstance(rows, dict):
            raise ViewpointError(f"{source}: field 'viewpoints' must be an object")
        out = cls()
        for key, row in rows.items():
            where = f"{source}: viewpoints.{key}"
            if not key.isdigit() or not 1 <= int(key) <= SLOTS:
                raise ViewpointError(f"{where}: a slot is 1..{SLOTS}")
            if not isinstance(row, dict) or set(row) != {"eye", "target", "fov_deg"}:
                raise ViewpointError(f"{where}: want exactly eye, target and fov_deg")
            eye, target, fov = row["eye"], row["target"], row["fov_deg"]
            for name, vec in (("eye", eye), ("target", target)):
                if not (
                    isinstance(vec, list)
                    and len(vec) == 3
                    and all(isinstance(v, int | float) and math.isfinite(v) for v in vec)
                ):
                    raise ViewpointError(f"{where}.{name}: want three finite numbers")
            if not isinstance(fov, int | float) or not 5.0 <= fov <= 150.0:
                raise ViewpointError(f"{where}.fov_deg: want 5..150 degrees")
            if math.dist(eye, target) < 1e-6:
                raise ViewpointError(f"{where}: eye and target are the same point")
            out.slots[int(key)] = Camera(
                f"view {key}", tuple(float(v) for v in eye), tuple(float(v) for v in target),  # type: ignore[arg-type]
                float(fov),
            )  # fmt: skip
        return out

    @classmethod
    def load(cls, path: Path) -> Viewpoints:
        """The store in ``path``; an empty one when the file does not exist."""
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return cls()
        except (OSError, UnicodeDecodeError) as exc:
            raise ViewpointError(f"{path}: cannot read it ({exc})") from None
        return cls.from_json(text, str(path))

    def save(self, path: Path) -> None:
        """Write the store to ``path`` (its folder made if needed), replacing it whole."""
        path.parent.mkdir(parents=True, exist_ok=True)
        part = path.with_name(path.name + ".part")
        part.write_text(self.to_json(), encoding="utf-8")
        part.replace(path)


def _check_slot(slot: int) -> None:
    if not 1 <= slot <= SLOTS:
        raise ViewpointError(f"viewpoint slot {slot}: want 1..{SLOTS}")
