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

from livedrummer.body.skeleton import SegmentLengths
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
    "stage",
    "front",
    "drummer",
    "overhead",
    "left",
    "right",
    "back",
    "kick",
)


#: The frame's aspect the stored viewpoints are fitted to (width / height: 16:9 video).
FRAME_ASPECT = 16.0 / 9.0
#: Share of the frame's half-height and half-width the drummer's figure may fill.
FILL = 0.86
#: How far the ``front`` camera looks down past the line from the hands over the highest drum
#: in front of them (degrees), and the least it looks down.
FRONT_CLEAR_DEG, FRONT_MIN_DEG = 6.0, 14.0


def figure_points(kit: Kit, lengths: SegmentLengths | None = None) -> np.ndarray:
    """Points (N, 3) that the drummer's body reaches, seated at ``kit`` with ``lengths``
    (the default body's without): the top of the head and the shoulders of the neutral seated
    pose, the elbows' reach either side, the hands over the drums and the hi-hat, the feet on
    the pedals. Cameras frame these, not the kit's bounding box."""
    from livedrummer.body.rig import neutral_world
    from livedrummer.body.secondary import SecondaryParams
    from livedrummer.body.skeleton import J, build_skeleton

    skel = build_skeleton(lengths, kit.seat_height_m)
    _q, world = neutral_world(skel, SecondaryParams().lean_deg)
    pose = world[0]
    top = pose[J["head_top"]] + (0.0, 0.0, 0.05)  # hair over the skull's top
    pts = [top, pose[J["r_shoulder"]], pose[J["l_shoulder"]]]
    elbow = skel.lengths.upper_arm * 0.8
    for side in ("r", "l"):
        pts.append(
            pose[J[f"{side}_shoulder"]]
            + (np.sign(pose[J[f"{side}_shoulder"]][0]) * elbow, 0.0, -skel.lengths.upper_arm)
        )
    for piece in kit.pieces:
        if piece.pedal_position_m is not None:
            pts.append(np.asarray(piece.pedal_position_m, float))
        if not piece.kind.is_cymbal or piece.pedal_position_m is not None:
            if piece.radius_m < 0.26:  # the drums and hi-hat the hands play; not the kick
                pts.append(np.asarray(piece.position_m, float) + np.array([0.0, 0.0, 0.05]))
        if piece.pedal_position_m is not None and not piece.kind.is_cymbal:
            # the kick's resonant head, nearest the audience: its bottom edge on the floor
            front = np.asarray(piece.position_m, float) - piece.normal * piece.depth_m
            pts.append(front - np.array([0.0, 0.0, piece.radius_m * 0.8]))
    return np.array(pts, float)


def fit_distance(
    points: np.ndarray,
    target: np.ndarray,
    direction: np.ndarray,
    fov_deg: float,
    aspect: float = FRAME_ASPECT,
    fill: float = FILL,
) -> float:
    """The distance from ``target`` along unit ``direction`` (towards the eye) at which every
    point lies inside ``fill`` of the frame (vertical field ``fov_deg``, ``aspect``)."""
    view = look_at(target + direction, target)
    rel = points - target
    cam = rel @ view[:3, :3].T  # right, up, back (+z towards the eye)
    tan_v = math.tan(math.radians(fov_deg) / 2.0) * fill
    tan_h = tan_v * aspect
    need = np.maximum(np.abs(cam[:, 0]) / tan_h, np.abs(cam[:, 1]) / tan_v) + cam[:, 2]
    return float(need.max())


def front_elevation_deg(kit: Kit, points: np.ndarray) -> float:
    """How far ``front`` looks down: enough that the hands (over the snare) are seen over the
    highest drum between them and the audience, at least :data:`FRONT_MIN_DEG`."""
    snares = [p for p in kit.pieces if p.kind.value == "snare"]
    if not snares:
        return FRONT_MIN_DEG
    hand = np.asarray(snares[0].position_m, float) + np.array([0.0, -0.08, 0.22])
    worst = FRONT_MIN_DEG - FRONT_CLEAR_DEG
    for p in kit.pieces:
        pos = np.asarray(p.position_m, float)
        rim = pos[2] + p.radius_m * max(0.0, 1.0 - abs(p.normal[2]))  # a tilted drum's top
        dy = pos[1] - p.radius_m * 0.5 - hand[1]
        if p.kind.is_cymbal or dy <= 0.02 or abs(pos[0] - hand[0]) > 0.45:
            continue
        worst = max(worst, math.degrees(math.atan2(rim - hand[2], dy)))
    return worst + FRONT_CLEAR_DEG


def kit_cameras(kit: Kit, lengths: SegmentLengths | None = None) -> dict[str, Camera]:
    """The eight stored viewpoints around ``kit``, framing the body of a drummer with
    ``lengths`` (the default body's without) head to hands and feet (:func:`figure_points`)."""
    pts = np.array([p.position_m for p in kit.pieces]) if kit.pieces else np.zeros((1, 3))
    cx, cy = (float(v) for v in pts[:, :2].mean(axis=0))
    cz = 0.75
    c = np.array([cx, cy * 0.6, cz])
    figure = figure_points(kit, lengths)
    lo, hi = figure.min(axis=0), figure.max(axis=0)
    centre = (lo + hi) / 2.0
    head_z = float(hi[2]) - 0.18  # the face, below the top of the head
    head = (0.0, 0.23, head_z)  # just in front of the face

    def cam(
        name: str, offset: tuple[float, float, float], fov: float = 40.0, drop: float = 0.0
    ) -> Camera:
        at = c - (0.0, 0.0, drop)
        return Camera(name, tuple(float(v) for v in at + offset), tuple(float(v) for v in at), fov)  # type: ignore[arg-type]

    def framed(name: str, azimuth_deg: float, elevation_deg: float, fov: float = 36.0) -> Camera:
        az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
        d = np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])
        dist = fit_distance(figure, centre, d, fov)
        eye = centre + d * dist
        return Camera(name, tuple(float(v) for v in eye), tuple(float(v) for v in centre), fov)  # type: ignore[arg-type]

    cams = [
        # front and stage fill the frame with the drummer's figure, head to hands and feet
        framed("stage", 30.0, 24.0),
        framed("front", 0.0, front_elevation_deg(kit, figure)),
        Camera("drummer", head, (cx, 0.75, 0.62), 70.0),
        cam("overhead", (0.0, 0.2, 3.6)),
        framed("left", -90.0, 8.0),
        framed("right", 90.0, 8.0),
        framed("back", 180.0, 20.0),
        Camera("kick", (cx + 0.5, cy + 1.6, 0.32), (cx, cy * 0.5, 0.62), 55.0),
    ]
    return {c_.name: c_ for c_ in cams}


def pick_camera(kit: Kit, name: str, lengths: SegmentLengths | None = None) -> Camera:
    cams = kit_cameras(kit, lengths)
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
