"""The drummer's skeleton: joints, parents, segment lengths and the seated rest pose.

One fixed hierarchy (pelvis at the root; spine, neck and head; two arms ending in a stick
tip; two legs ending at the ball of the foot) so that every later stage can index joints by
constant integers and vectorize over time. The hierarchy is the one of SMED's figure 4.6
(pelvis, lower back, upper back, neck, head; shoulder, elbow, wrist; hip, knee, ankle), with a
stick joint (the grip fulcrum) added as the arm's last segment, as in the virtual-drummer
paper. SMED's figure gives the segment lengths only as a drawing, so the defaults below are
ordinary adult proportions (1.78 m tall, 16" stick held at a third of its length); every
length is a field of :class:`SegmentLengths` and can be changed.

Rest pose (all local rotations identity): upright torso, arms hanging straight down with the
sticks pointing down in line with the hands, legs straight down, feet pointing forward. Bone
offsets are expressed in the parent joint's frame, so a joint's rotation turns every bone
below it. The *seated* pose is produced by :mod:`livedrummer.body.ik`, not stored here.
Limits: no fingers, no clavicle motion, rigid feet.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

JOINTS: tuple[str, ...] = (
    "pelvis", "lower_back", "chest", "neck", "head", "head_top",
    "r_shoulder", "r_elbow", "r_wrist", "r_stick", "r_tip",
    "l_shoulder", "l_elbow", "l_wrist", "l_stick", "l_tip",
    "r_hip", "r_knee", "r_ankle", "r_toe",
    "l_hip", "l_knee", "l_ankle", "l_toe",
)  # fmt: skip
J = {name: i for i, name in enumerate(JOINTS)}
N_JOINTS = len(JOINTS)

PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3, 4,
    2, 6, 7, 8, 9,
    2, 11, 12, 13, 14,
    0, 16, 17, 18,
    0, 20, 21, 22,
)  # fmt: skip

#: Leaf joints carry no rotation of their own (BVH writes them as End Sites).
LEAVES: frozenset[int] = frozenset({J["head_top"], J["r_tip"], J["l_tip"], J["r_toe"], J["l_toe"]})

#: Per arm: shoulder, elbow, wrist, stick, tip; per leg: hip, knee, ankle, toe.
ARM = {
    "R": (J["r_shoulder"], J["r_elbow"], J["r_wrist"], J["r_stick"], J["r_tip"]),
    "L": (J["l_shoulder"], J["l_elbow"], J["l_wrist"], J["l_stick"], J["l_tip"]),
}
LEG = {
    "R": (J["r_hip"], J["r_knee"], J["r_ankle"], J["r_toe"]),
    "L": (J["l_hip"], J["l_knee"], J["l_ankle"], J["l_toe"]),
}


@dataclass(frozen=True, slots=True)
class SegmentLengths:
    """Segment lengths in metres (symmetrical body)."""

    pelvis_height: float = 0.10  # seat surface to hip/pelvis joint
    lower_back: float = 0.12  # pelvis to lower-back joint
    upper_back: float = 0.22  # lower back to chest joint
    chest_to_shoulder: float = 0.20  # chest joint up to the shoulder line
    shoulder_half_width: float = 0.19
    neck: float = 0.24  # chest joint to neck base
    head: float = 0.12  # neck base to head joint (skull base)
    head_top: float = 0.14
    upper_arm: float = 0.30
    forearm: float = 0.27
    hand: float = 0.08  # wrist to the grip fulcrum
    stick: float = 0.30  # fulcrum to stick tip
    hip_half_width: float = 0.10
    hip_forward: float = 0.04
    thigh: float = 0.45
    shin: float = 0.44
    foot: float = 0.15  # ankle to ball of the foot

    def check(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not 0.0 < value < 1.5:
                raise ValueError(f"segment {f.name} must be in (0, 1.5) m, got {value}")


@dataclass(frozen=True)
class Skeleton:
    """Offsets of every joint from its parent (rest pose) and the root's seated position."""

    lengths: SegmentLengths
    offsets: np.ndarray  # (N_JOINTS, 3) float64, in the parent's frame
    root_m: np.ndarray  # (3,) pelvis position in the kit frame

    @property
    def arm_reach(self) -> float:
        """Shoulder to stick tip, arm and stick in one straight line."""
        s = self.lengths
        return s.upper_arm + s.forearm + s.hand + s.stick


def build_skeleton(lengths: SegmentLengths | None = None, seat_height_m: float = 0.52) -> Skeleton:
    s = lengths or SegmentLengths()
    s.check()
    off = np.zeros((N_JOINTS, 3))
    off[J["lower_back"]] = (0.0, 0.0, s.lower_back)
    off[J["chest"]] = (0.0, 0.0, s.upper_back)
    off[J["neck"]] = (0.0, 0.0, s.neck)
    off[J["head"]] = (0.0, 0.0, s.head)
    off[J["head_top"]] = (0.0, 0.0, s.head_top)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        off[J[f"{side}_shoulder"]] = (sign * s.shoulder_half_width, 0.0, s.chest_to_shoulder)
        off[J[f"{side}_elbow"]] = (0.0, 0.0, -s.upper_arm)
        off[J[f"{side}_wrist"]] = (0.0, 0.0, -s.forearm)
        off[J[f"{side}_stick"]] = (0.0, 0.0, -s.hand)
        off[J[f"{side}_tip"]] = (0.0, 0.0, -s.stick)
        off[J[f"{side}_hip"]] = (sign * s.hip_half_width, s.hip_forward, 0.0)
        off[J[f"{side}_knee"]] = (0.0, 0.0, -s.thigh)
        off[J[f"{side}_ankle"]] = (0.0, 0.0, -s.shin)
        off[J[f"{side}_toe"]] = (0.0, s.foot, 0.0)
    root = np.array([0.0, 0.0, seat_height_m + s.pelvis_height])
    return Skeleton(lengths=s, offsets=off, root_m=root)


#: Rest direction of each joint's bone (towards its main child) and a rest "side" vector
#: fixing the bone's twist, used by the IK to turn world directions into rotations.
BONE_REST_DIR = np.array([0.0, 0.0, -1.0])
BONE_REST_SIDE = np.array([1.0, 0.0, 0.0])
FOOT_REST_DIR = np.array([0.0, 1.0, 0.0])
FOOT_REST_SIDE = np.array([1.0, 0.0, 0.0])
