"""The drummer and the sticks: a skinned avatar, or capsules and balls, and two stick segments.

The drummer is a skinned avatar (:class:`~services.display.avatar_gl.SkinnedDraw`) posed by the
frame's world rotations and joint positions on the GPU, or, with ``avatar="mannequin"``, for a
frame without rotations or a skeleton other than the body's 24 joints, a capsule mannequin: the
joint positions gathered by the skeleton's parent index (one numpy gather, no per-joint loop)
into segment instances whose basis the segment shader builds on the GPU, and a ball per joint.
The sticks are two more segments, drawn either way. The lit and the depth-only arrays read the
same instance buffers, so the shadow pass draws what the scene pass draws. Limits: the avatar's
BLEND parts cast no shadow (:meth:`SkinnedDraw.draw_depth`).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.body.face import FaceTrack
from livedrummer.body.skeleton import N_JOINTS, J
from livedrummer.render.body_reach import BodyReach, SkinBoxes
from livedrummer.render.kitmesh import MATERIAL_PLAIN
from livedrummer.render.scene import CH_HIGHLIGHT, SceneFrame, Skeleton, Tone

from ..avatar_gl import SkinnedDraw
from .gpu import Gpu

#: colour per :class:`Tone`
PALETTE = np.zeros((len(Tone), 3), np.float32)
PALETTE[Tone.SHIRT] = (0.14, 0.26, 0.50)
PALETTE[Tone.TROUSERS] = (0.10, 0.10, 0.12)
PALETTE[Tone.SKIN] = (0.82, 0.60, 0.46)
PALETTE[Tone.SHOES] = (0.85, 0.85, 0.85)
PALETTE[Tone.HAIR] = (0.12, 0.07, 0.04)
STICK_COLOR = (0.80, 0.60, 0.34)
STICK_RADIUS_M = 0.0075
SEGMENT_FLOATS = 15  # a xyz, b xyz, radius, colour rgba, material
BALL_FLOATS = 12  # centre xyz radius, colour rgba, material
#: metres a face shape moves a vertex at most (added to a skinned drummer's boxes)
FACE_MARGIN_M = 0.05
#: boxes a stick is cut into for its shadow (a slanted stick's one box would be mostly air)
STICK_PIECES = 4
_SEGMENT = ("3f 3f 1f 4f 4f/i", "in_a", "in_b", "in_radius", "in_color", "in_material")
_BALL = ("4f 4f 4f/i", "in_centre_radius", "in_color", "in_material")


class BodyDraw:
    """One skeleton's drummer and sticks (see the module docstring)."""

    def __init__(
        self,
        gpu: Gpu,
        skeleton: Skeleton | None,
        kit_crash_like: np.ndarray,
        avatar: Avatar | Literal["mannequin"] | None,
    ) -> None:
        self.skeleton = skeleton
        sk = skeleton
        material = np.array([0.0, 14.0, MATERIAL_PLAIN, 0.0], np.float32)
        if sk is None:
            self._bones = np.zeros(0, np.int64)
            self._balls = np.zeros(0, np.int64)
        else:
            self._bones = sk.bones[sk.segment_radius_m[sk.bones] > 0]
            self._balls = np.flatnonzero(sk.joint_radius_m > 0)
        nb = len(self._bones)
        seg = np.zeros((nb + 2, SEGMENT_FLOATS), np.float32)
        if sk is not None:
            seg[:nb, 6] = sk.segment_radius_m[self._bones]
            seg[:nb, 7:10] = PALETTE[sk.tone[self._bones]]
        seg[nb:, 6] = STICK_RADIUS_M
        seg[nb:, 7:10] = STICK_COLOR
        seg[:, 11:15] = material
        self._seg = seg
        ball = np.zeros((len(self._balls), BALL_FLOATS), np.float32)
        if sk is not None:
            ball[:, 3] = sk.joint_radius_m[self._balls]
            ball[:, 4:7] = PALETTE[sk.tone[self._balls]]
        ball[:, 8:12] = material
        self._ball = ball
        ctx = gpu.ctx
        seg_buf = ctx.buffer(reserve=seg.nbytes, dynamic=True)
        ball_buf = ctx.buffer(reserve=max(ball.nbytes, 4), dynamic=True)
        self._bufs = (seg_buf, ball_buf)
        self._lit = (
            gpu.vao("segment", "limb", seg_buf, *_SEGMENT),
            gpu.vao("ball", "sphere", ball_buf, *_BALL),
        )
        self._depth = (
            gpu.vao("depth_segment", "limb", seg_buf, *_SEGMENT),
            gpu.vao("depth_ball", "sphere", ball_buf, *_BALL),
        )
        self._depth_skin = gpu.programs["depth_skin"]
        self.skinned: SkinnedDraw | None = None
        if skeleton is not None and skeleton.size == N_JOINTS and avatar != "mannequin":
            if avatar is None:
                from livedrummer.avatar.character import build_character

                avatar = build_character()
            self.skinned = SkinnedDraw(ctx, gpu.programs["skin"], avatar)
        self._face: FaceTrack | None = None  # blinks, looks and reactions (body.face)
        if self.skinned is not None and self.skinned.has_face:
            self._face = FaceTrack(kit_crash_like)
        self._pose: tuple[np.ndarray, np.ndarray] | None = None
        self._capsule_reach: BodyReach | None = None
        if sk is not None:
            self._capsule_reach = BodyReach.from_capsules(
                sk.parent,
                self._bones,
                sk.segment_radius_m[self._bones],
                self._balls,
                sk.joint_radius_m[self._balls],
            )
        self._skin_boxes: SkinBoxes | None = None
        if self.skinned is not None:
            mesh = self.skinned.avatar.mesh
            self._skin_boxes = SkinBoxes(mesh.positions, mesh.joints, mesh.weights)
        self._counts = (0, 0)  # segments and balls drawn
        #: whether a drummer is drawn (False for a frame of None: the kit at rest)
        self.shown = False

    @property
    def has_blend(self) -> bool:
        """Whether the avatar has transparent (BLEND) parts, drawn blended in draw order."""
        if self.skinned is None:
            return False
        mesh = self.skinned.avatar.mesh
        return any(mesh.materials[p.material].alpha_mode == "BLEND" for p in mesh.primitives)

    def caster_boxes(self, frame: SceneFrame, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Boxes (lo (B, 3), hi (B, 3)) that hold everything drawn of the drummer and the
        sticks for ``frame`` (uploaded last), grown by ``margin_m``
        (:class:`livedrummer.render.body_reach.BodyReach`)."""
        ends = frame.sticks_m.reshape(2, 1, 2, 3)
        steps = np.linspace(0.0, 1.0, STICK_PIECES + 1)[None, :, None]
        along = ends[:, :, 0] + steps * (ends[:, :, 1] - ends[:, :, 0])  # (2, pieces + 1, 3)
        pieces = np.stack([along[:, :-1], along[:, 1:]], axis=2).reshape(-1, 2, 3)
        lo = [pieces.min(axis=1) - STICK_RADIUS_M]
        hi = [pieces.max(axis=1) + STICK_RADIUS_M]
        if self._pose is not None and self._skin_boxes is not None and self.skinned is not None:
            skin_m = self.skinned.skin_matrices(*self._pose)
            b_lo, b_hi = self._skin_boxes.boxes(skin_m, FACE_MARGIN_M)
            lo.append(b_lo)
            hi.append(b_hi)
        elif self._capsule_reach is not None and len(frame.joints_m):
            b_lo, b_hi = self._capsule_reach.boxes(frame.joints_m, 0.0)
            lo.append(b_lo)
            hi.append(b_hi)
        return np.concatenate(lo) - margin_m, np.concatenate(hi) + margin_m

    def upload(self, frame: SceneFrame | None) -> None:
        """Copy one frame's joints and sticks into the instance buffers (checked already)."""
        self.shown = frame is not None
        if frame is None:
            return
        nb = len(self._bones)
        has_body = self.skeleton is not None and len(frame.joints_m) > 0
        self._pose = None
        if has_body and self.skinned is not None and frame.rotations_q is not None:
            self._pose = (frame.rotations_q, frame.joints_m)
            if self._face is not None:
                self.skinned.set_face(
                    self._face.weights(
                        frame.time_s, frame.channels[:, CH_HIGHLIGHT], frame.rotations_q[J["head"]]
                    )
                )
            has_body = False  # the avatar, not the capsules; the sticks stay
        seg_count = len(self._seg) if has_body else 2
        if has_body and self.skeleton is not None:
            j = frame.joints_m
            self._seg[:nb, 0:3] = j[self.skeleton.parent[self._bones]]
            self._seg[:nb, 3:6] = j[self._bones]
            self._ball[:, 0:3] = j[self._balls]
        self._seg[nb:, 0:6] = frame.sticks_m.reshape(2, 6)
        seg_buf, ball_buf = self._bufs
        seg_buf.write(self._seg[nb:].tobytes() if not has_body else self._seg.tobytes())
        ball_count = len(self._ball) if has_body else 0
        if ball_count:
            ball_buf.write(self._ball.tobytes())
        self._counts = (seg_count, ball_count)

    def draw(self, fbo: Any) -> None:
        """The drummer and the sticks lit into ``fbo`` (bound already)."""
        if not self.shown:
            return
        if self._pose is not None and self.skinned is not None:
            self.skinned.draw(*self._pose, fbo)
        self._render(self._lit)

    def draw_depth(self) -> None:
        """The drummer and the sticks into the bound framebuffer's depth (the shadow map)."""
        if not self.shown:
            return
        if self._pose is not None and self.skinned is not None:
            self.skinned.draw_depth(self._depth_skin, *self._pose)
        self._render(self._depth)

    def _render(self, vaos: tuple[Any, Any]) -> None:
        seg_count, ball_count = self._counts
        vaos[0].render(instances=seg_count)
        if ball_count:
            vaos[1].render(instances=ball_count)
