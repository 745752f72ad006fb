"""The scene contract between the body model and the renderer: plain arrays, no OpenGL.

The body model produces, per video or display frame, where every joint *is* (world positions in
the kit frame of :mod:`livedrummer.kit.model`: metres, +x right, +y forward, +z up), where the two
sticks are, and what each kit piece is doing. The renderer draws whatever it is given and
never asks the body why; so a recorded pose file, a test, or a rest pose can stand in for the
body without the renderer noticing.

A :class:`Skeleton` is the static part: joint names, the parent of each joint (-1 for a root),
the radius of the capsule drawn from the parent to the joint, the radius of the ball drawn at
the joint (the head is just a joint with a large ball) and a tone per joint (costume, skin, ...)
that picks a colour from the renderer's palette. A :class:`SceneFrame` is the moving part: one
float32 ``(J, 3)`` array of joint positions, a ``(2, 2, 3)`` array of stick segments
(``[stick, butt|tip, xyz]``, right hand's stick first) and a ``(P, 5)`` array of kit channels,
one row per ``kit.pieces`` entry, with the columns named by the ``CH_*`` indices below. A
frame with no joints (shape ``(0, 3)``) draws no drummer: the kit and the sticks only.

A frame may also carry ``rotations_q``, the joints' *world* rotations (float32 ``(J, 4)``
quaternions, w x y z, each orienting the joint's bone towards its child), which a skinned
avatar needs (:mod:`livedrummer.avatar`); the body's frames always carry them, a frame without
them (``None``: a test's stand-in pose) is drawn as capsules. Limits: the capsules use joint
positions only, so they cannot twist visibly; the sticks are straight segments. Arrays are
validated by shape and dtype once per frame (:meth:`SceneFrame.check`), not by value: NaN
joints are the body's bug.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from livedrummer.errors import LivedrummerError

#: Kit channel columns: a hit highlight in 0..1 (SMED's skin highlighting), the angle in
#: radians a cymbal or drum is tilted away from rest by the hit (wobble), the azimuth in radians
#: of the axis the wobble tilts about, a piece-specific travel: the hi-hat top cymbal's lift
#: above the bottom one in metres, or the kick beater's angle back from the head in radians,
#: and the footboard's turn up from rest about its heel hinge in radians (pedal).
CH_HIGHLIGHT = 0
CH_WOBBLE = 1
CH_WOBBLE_AZIMUTH = 2
CH_TRAVEL = 3
CH_PEDAL = 4
N_CHANNELS = 5


class SceneError(LivedrummerError):
    """A skeleton or a frame does not have the shape the renderer was told to expect."""


class Tone(IntEnum):
    """Palette entries the renderer colours a joint's capsule and ball with."""

    SHIRT = 0
    TROUSERS = 1
    SKIN = 2
    SHOES = 3
    HAIR = 4


@dataclass(frozen=True)
class Skeleton:
    """Joint names, parents and drawing radii (see the module docstring)."""

    names: tuple[str, ...]
    parent: np.ndarray  # int32 (J,), -1 for a root; a parent precedes its child
    segment_radius_m: np.ndarray  # float32 (J,), capsule from parent to this joint
    joint_radius_m: np.ndarray  # float32 (J,), ball at this joint
    tone: np.ndarray  # uint8 (J,), Tone values

    def __post_init__(self) -> None:
        n = len(self.names)
        for field in ("parent", "segment_radius_m", "joint_radius_m", "tone"):
            arr = getattr(self, field)
            if np.shape(arr) != (n,):
                raise SceneError(f"skeleton field {field!r} has shape {np.shape(arr)}, want ({n},)")
        parent = np.asarray(self.parent)
        bad = np.flatnonzero((parent >= np.arange(n)) | (parent < -1))
        if bad.size:
            j = int(bad[0])
            raise SceneError(
                f"skeleton joint {self.names[j]!r} has parent {int(parent[j])}: a parent must "
                "be an earlier joint or -1"
            )

    @classmethod
    def build(
        cls,
        joints: list[tuple[str, str | None, float, float, Tone]],
    ) -> Skeleton:
        """From ``(name, parent name or None, segment radius, joint radius, tone)`` rows."""
        names = tuple(row[0] for row in joints)
        index = {name: i for i, name in enumerate(names)}
        missing = [row[1] for row in joints if row[1] is not None and row[1] not in index]
        if missing:
            raise SceneError(f"skeleton parent {missing[0]!r} is not a joint")
        return cls(
            names=names,
            parent=np.array([-1 if r[1] is None else index[r[1]] for r in joints], np.int32),
            segment_radius_m=np.array([r[2] for r in joints], np.float32),
            joint_radius_m=np.array([r[3] for r in joints], np.float32),
            tone=np.array([int(r[4]) for r in joints], np.uint8),
        )

    @property
    def size(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise SceneError(f"skeleton has no joint {name!r}") from None

    @property
    def bones(self) -> np.ndarray:
        """Indices of the joints that have a parent (one capsule each)."""
        return np.flatnonzero(self.parent >= 0)


@dataclass(frozen=True)
class SceneFrame:
    """Everything that moves in one frame (see the module docstring)."""

    joints_m: np.ndarray  # float32 (J, 3)
    sticks_m: np.ndarray  # float32 (2, 2, 3): [stick, butt|tip, xyz]
    channels: np.ndarray  # float32 (P, N_CHANNELS): CH_* columns per kit piece
    time_s: float = 0.0
    rotations_q: np.ndarray | None = None  # float32 (J, 4) world rotations, w x y z; or None

    def check(self, skeleton: Skeleton | None, pieces: int) -> None:
        """Raise :class:`SceneError` unless the arrays fit ``skeleton`` and a kit of ``pieces``."""
        joints = (
            self.joints_m.shape[0] if skeleton is None or not len(self.joints_m) else skeleton.size
        )
        want = {
            "joints_m": (joints, 3),
            "sticks_m": (2, 2, 3),
            "channels": (pieces, N_CHANNELS),
        }
        if self.rotations_q is not None:
            want["rotations_q"] = (self.joints_m.shape[0], 4)
        for field, shape in want.items():
            arr = getattr(self, field)
            if arr.shape != shape or arr.dtype != np.float32:
                raise SceneError(
                    f"frame field {field!r} is {arr.dtype}{arr.shape}, want float32{shape}"
                )


def empty_channels(pieces: int) -> np.ndarray:
    """A kit at rest: no highlight, no wobble, hi-hat closed, beater at the head, boards down."""
    return np.zeros((pieces, N_CHANNELS), np.float32)
