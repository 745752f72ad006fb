"""The body model as the renderer's scene: skeleton, joints, sticks and kit channels per frame.

The body (:mod:`livedrummer.body`) samples a performance into pose records
(:mod:`livedrummer.body.pose`); the renderer draws :class:`~livedrummer.render.scene.SceneFrame` s.
This module is the whole mapping between the two, so there is one motion model and one kit-channel
model (the body's), and the renderer never learns how either is computed.

* Joints: the scene :data:`BODY_SKELETON` has the body's 24 joints in the body's order with the
  body's parents, so a frame's ``joints_m`` *is* the record's ``position`` field (no gather).
  Radii and tones are drawing choices made here; the stick-tip joints get zero radii (the
  sticks are drawn as sticks).
* Sticks: from the tip through the grip fulcrum (the body's ``*_stick`` joint) and on past it by
  the stick's tail behind the hand (:data:`STICK_TAIL_M`), right stick first.
* Rotations: the body's world joint rotations (the records carry local ones; the product
  down the parent chain, :func:`world_rotations`), which a skinned avatar is posed with.
* Kit channels: ``glow`` is the highlight; ``swing`` is a cymbal's swing or a drum's shake
  (wobble), and for the kick the beater's angle back from the head, which the scene calls
  travel; ``lift`` (the hi-hat top cymbal's height above closed, metres) is the hi-hat's
  travel. On both pedal pieces the swing also gives the foot's lift, from which the footboard's
  angle (pedal) is computed so the board stays under the ball of the foot. Which piece does
  what is :data:`livedrummer.kit.behaviour.BEHAVIOURS`. A piece wobbles about the horizontal
  axis across the line from it to the throne, so a positive swing dips the edge nearest the
  drummer, where the stick lands.

Frames are made for many times at once (:meth:`BodyScene.frames` samples in chunks, so memory
stays bounded on long files). Limits: the body's pose is used as given (no smoothing between
samples); a performance with no onsets is drawn in the body's neutral pose.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from livedrummer.body import quat
from livedrummer.body.animation import FOOT_LIFT_M
from livedrummer.body.expression import Expression
from livedrummer.body.perform import Performed, perform
from livedrummer.body.rig import build_rig
from livedrummer.body.sample import sample_poses
from livedrummer.body.skeleton import JOINTS, PARENTS, J
from livedrummer.body.strokes import StrokeParams
from livedrummer.kit.behaviour import BEHAVIOURS, HitMotion, PedalMotion, footboard_angle
from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import NoteMap
from livedrummer.render.scene import (
    CH_HIGHLIGHT,
    CH_PEDAL,
    CH_TRAVEL,
    CH_WOBBLE,
    CH_WOBBLE_AZIMUTH,
    N_CHANNELS,
    SceneFrame,
    Skeleton,
    Tone,
)
from livedrummer.sticking.result import Sticking
from livedrummer.timeline.performance import Performance

#: A 16" stick held a third of the way up: the part behind the grip fulcrum (m).
STICK_TAIL_M = 0.11
CHUNK_FRAMES = 2048

#: joint -> (segment radius from its parent, ball radius at the joint, tone), in metres.
_LOOK: dict[str, tuple[float, float, Tone]] = {
    "pelvis": (0.0, 0.12, Tone.TROUSERS),
    "lower_back": (0.12, 0.12, Tone.SHIRT),
    "chest": (0.13, 0.12, Tone.SHIRT),
    "neck": (0.12, 0.05, Tone.SKIN),
    "head": (0.05, 0.0, Tone.SKIN),
    "head_top": (0.085, 0.088, Tone.HAIR),
    "shoulder": (0.06, 0.06, Tone.SHIRT),
    "elbow": (0.05, 0.045, Tone.SHIRT),
    "wrist": (0.038, 0.034, Tone.SKIN),
    "stick": (0.034, 0.036, Tone.SKIN),
    "tip": (0.0, 0.0, Tone.SKIN),
    "hip": (0.09, 0.08, Tone.TROUSERS),
    "knee": (0.075, 0.06, Tone.TROUSERS),
    "ankle": (0.055, 0.045, Tone.TROUSERS),
    "toe": (0.045, 0.04, Tone.SHOES),
}


def _body_skeleton() -> Skeleton:
    rows: list[tuple[str, str | None, float, float, Tone]] = []
    for name, parent in zip(JOINTS, PARENTS, strict=True):
        seg, ball, tone = _LOOK.get(name) or _LOOK[name.split("_", 1)[1]]
        # the tone of a segment is its child's; the upper chest (chest -> neck) is shirt
        if name == "neck":
            tone = Tone.SHIRT
        rows.append((name, None if parent < 0 else JOINTS[parent], seg, ball, tone))
    return Skeleton.build(rows)


#: The body's joints as a scene skeleton (see the module docstring).
BODY_SKELETON = _body_skeleton()
_STICKS = np.array([[J["r_stick"], J["r_tip"]], [J["l_stick"], J["l_tip"]]])


def stick_segments(position: np.ndarray) -> np.ndarray:
    """(..., 2, 2, 3) float32 ``[stick, butt|tip, xyz]`` from body positions (..., 24, 3)."""
    grip = position[..., _STICKS[:, 0], :]
    tip = position[..., _STICKS[:, 1], :]
    along = tip - grip
    length = np.linalg.norm(along, axis=-1, keepdims=True)
    butt = grip - STICK_TAIL_M * along / np.maximum(length, 1e-9)
    return np.stack([butt, tip], axis=-2).astype(np.float32)


def channel_roles(kit: Kit) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per piece: swing is wobble, swing is travel, lift is travel (bool (P,)), wobble azimuth
    (from :data:`~livedrummer.kit.behaviour.BEHAVIOURS`)."""
    looks = [BEHAVIOURS[p.kind] for p in kit.pieces]
    wobbles = np.array(
        [b.hit is not HitMotion.NONE and b.pedal is PedalMotion.NONE for b in looks], bool
    )
    beater = np.array([b.pedal is PedalMotion.BEATER for b in looks], bool)
    lifts = np.array([b.pedal is PedalMotion.HIHAT for b in looks], bool)
    pos = np.array([p.position_m for p in kit.pieces], np.float64).reshape(-1, 3)
    azimuth = np.arctan2(-pos[:, 1], -pos[:, 0]) + np.pi / 2
    return wobbles, beater, lifts, azimuth


def footboard_channel(poses: np.ndarray, kit: Kit) -> np.ndarray:
    """Footboard angles (F, P) from the pose records: the body's swing on a pedal piece is
    ``pedal_swing_rad`` per unit of foot lift, and the board turns so that the ball of the foot,
    lifted ``FOOT_LIFT_M`` per unit, stays on it (a foot lifted further leaves the board)."""
    per_lift = np.array([BEHAVIOURS[p.kind].pedal_swing_rad for p in kit.pieces], np.float64)
    swing = np.asarray(poses["swing"], np.float64).reshape(-1, len(kit.pieces))
    lift = np.where(per_lift > 0, swing / np.where(per_lift > 0, per_lift, 1.0), 0.0)
    out: np.ndarray = np.where(per_lift > 0, footboard_angle(FOOT_LIFT_M * lift), 0.0)
    return out


def scene_channels(poses: np.ndarray, kit: Kit) -> np.ndarray:
    """Kit channels (F, P, N_CHANNELS) float32 of the scene from pose records (F,)."""
    wobbles, beater, lifts, azimuth = channel_roles(kit)
    out = np.zeros((poses.size, len(kit.pieces), N_CHANNELS), np.float32)
    out[..., CH_HIGHLIGHT] = poses["glow"]
    out[..., CH_WOBBLE] = np.where(wobbles, poses["swing"], 0.0)
    out[..., CH_WOBBLE_AZIMUTH] = azimuth
    out[..., CH_TRAVEL] = np.where(beater, poses["swing"], np.where(lifts, poses["lift"], 0.0))
    out[..., CH_PEDAL] = footboard_channel(poses, kit).reshape(out.shape[:-1])
    return out


def world_rotations(local_q: np.ndarray) -> np.ndarray:
    """World rotations (..., 24, 4) float32 from the records' local ones (..., 24, 4)."""
    local = np.asarray(local_q, np.float64)
    out = np.empty_like(local)
    out[..., 0, :] = local[..., 0, :]
    for j in range(1, len(JOINTS)):
        out[..., j, :] = quat.mul(out[..., PARENTS[j], :], local[..., j, :])
    return out.astype(np.float32)


def frame_from_pose(pose: np.ndarray, time_s: float, kit: Kit) -> SceneFrame:
    """The scene frame of one pose record (a live pose received over the wire)."""
    poses = np.asarray(pose).reshape(1)
    position = np.ascontiguousarray(poses["position"], np.float32)
    return SceneFrame(
        position[0],
        stick_segments(position)[0],
        scene_channels(poses, kit)[0],
        time_s,
        world_rotations(poses["rotation"])[0],
    )


@dataclass(frozen=True)
class BodyScene:
    """A performed performance on a kit, as scene frames at any times."""

    kit: Kit
    performed: Performed

    @classmethod
    def perform(
        cls,
        performance: Performance,
        kit: Kit,
        note_map: NoteMap,
        sticking: Sticking | None = None,
        expression: Expression | None = None,
        strokes: StrokeParams | None = None,
    ) -> BodyScene:
        """Fit the body to ``kit`` and animate ``performance`` with ``sticking`` (by default
        :func:`~livedrummer.sticking.strategy.stick_performance`'s: optimal on its grid)."""
        return cls(
            kit,
            perform(performance, build_rig(kit), note_map, expression, strokes, sticking=sticking),
        )

    def poses(self, times: np.ndarray) -> np.ndarray:
        """The body's pose records at ``times`` (seconds, float64)."""
        p = self.performed
        return sample_poses(p.animation, p.sticking, np.asarray(times, np.float64), p.chokes)

    def arrays(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Joints (F, 24, 3), sticks (F, 2, 2, 3) and channels (F, P, 4), all float32."""
        poses = self.poses(times)
        position = np.ascontiguousarray(poses["position"], np.float32)
        return position, stick_segments(position), scene_channels(poses, self.kit)

    def frames(self, times: np.ndarray, chunk: int = CHUNK_FRAMES) -> Iterator[SceneFrame]:
        """One frame per time, sampled ``chunk`` times at a go."""
        times = np.asarray(times, np.float64)
        for start in range(0, times.size, chunk):
            t = times[start : start + chunk]
            poses = self.poses(t)
            joints = np.ascontiguousarray(poses["position"], np.float32)
            sticks = stick_segments(joints)
            channels = scene_channels(poses, self.kit)
            rotations = world_rotations(poses["rotation"])
            for i in range(t.size):
                yield SceneFrame(joints[i], sticks[i], channels[i], float(t[i]), rotations[i])

    def frame_at(self, time_s: float) -> SceneFrame:
        return next(self.frames(np.array([time_s])))
