"""The scene pass: the kit, the drummer and the sticks, lit by the show's rig and shadowed.

It owns the kit's and the body's instance buffers (:class:`.kit.KitDraw`, :class:`.body.BodyDraw`)
and turns a frame and a camera into the uniforms every program reads (:meth:`ScenePass.frame`).
Drawing goes nearest and largest first, the floor last: hidden fragments fail the depth test
before they are shaded (llvmpipe tests depth early for these shaders). With
``kit_occludes_only`` the kit is drawn into depth only, before the body, so the body alone is
seen, hidden where the kit is in front of it (a practice teacher's ghost). Limits: every surface
is lit by the same rig; the kit's surfaces are opaque.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.render.camera import Camera
from livedrummer.render.kitmesh import STAGE_RADIUS_M, KitMesh
from livedrummer.render.lights import LightRig
from livedrummer.render.scene import SceneFrame, Skeleton, empty_channels

from .body import BodyDraw
from .gpu import Gpu
from .kit import KitDraw
from .shadow import key_light_view_projection

MAX_CELL_OTHERS = 128  # neighbours a stage floor's cell is cut by (shaders/floor_cell.glsl)


@dataclass(frozen=True)
class FrameView:
    """A frame's camera and key light: the uniforms and the two view-projections."""

    uniforms: dict[str, Any]
    view_proj: np.ndarray  # the camera's, row-major float32
    light_vp: np.ndarray  # the key spot's


class ScenePass:
    """The kit and the body of one renderer (see the module docstring)."""

    def __init__(
        self,
        gpu: Gpu,
        kit_mesh: KitMesh,
        skeleton: Skeleton | None,
        avatar: Avatar | Literal["mannequin"] | None,
    ) -> None:
        self._gpu = gpu
        self.kit_mesh = kit_mesh
        self.kit = KitDraw(gpu, kit_mesh)
        self.body = BodyDraw(gpu, skeleton, kit_mesh.crash_like, avatar)

    def upload(self, frame: SceneFrame | None) -> np.ndarray:
        """Copy one frame into the kit's and the body's buffers; the kit's instances."""
        km = self.kit_mesh
        channels = frame.channels if frame is not None else empty_channels(km.pieces)
        inst = km.instances(channels)
        self.kit.upload(inst)
        if frame is not None:
            frame.check(self.body.skeleton, km.pieces)
        self.body.upload(frame)
        return inst

    def centre(self) -> np.ndarray:
        """The kit's centre (its first instance's origin), or the origin for no kit."""
        km = self.kit_mesh
        return km.model[0, :3, 3] if len(km.model) else np.zeros(3)

    def frame(self, camera: Camera, aspect: float, lights: LightRig, shadows: bool) -> FrameView:
        """The uniforms of a frame seen from ``camera`` under ``lights``."""
        vp = camera.view_projection(aspect)
        centre = self.centre()
        eye = np.asarray(camera.eye, np.float32)
        target = np.array([centre[0], centre[1], 0.6])
        uniforms: dict[str, Any] = {
            "u_view_proj": vp.T.tobytes(),
            "u_eye": tuple(eye),
            "u_stage_centre": (float(centre[0]), float(centre[1]), 0.0),
            "u_stage_radius": STAGE_RADIUS_M,
            **lights.uniforms(target),
        }
        light_vp = key_light_view_projection(np.array(uniforms["u_key_pos"]), target)
        uniforms["u_light_vp"] = light_vp.T.tobytes()
        uniforms["u_shadow_on"] = int(shadows)
        return FrameView(uniforms, vp, light_vp)

    def floor_cell(self, others: np.ndarray) -> None:
        """The other drummers' pool centres that cut this kit's floor (a stage)."""
        prog = self._gpu.programs["floor"]
        if "u_cell_count" not in prog:
            return
        others = np.asarray(others, np.float32).reshape(-1, 2)[:MAX_CELL_OTHERS]
        prog["u_cell_count"].value = len(others)
        if len(others):
            padded = np.zeros((MAX_CELL_OTHERS, 2), np.float32)
            padded[: len(others)] = others
            prog["u_cell_others"].write(padded.tobytes())

    def draw(self, fbo: Any, view: FrameView, kit_occludes_only: bool) -> None:
        """The body then the kit, lit, into ``fbo`` (bound, its viewport set)."""
        if kit_occludes_only:
            self._kit_depth(fbo, view.view_proj)
        self.body.draw(fbo)
        if not kit_occludes_only:
            self.kit.draw(self._gpu.ctx)
        else:
            import moderngl

            self._gpu.ctx.disable(moderngl.BLEND)

    def _kit_depth(self, fbo: Any, vp: np.ndarray) -> None:
        """The kit (not the floor) into ``fbo``'s depth from the camera, no colour written."""
        self._gpu.programs["depth_mesh"]["u_view_proj"].write(vp.T.tobytes())
        fbo.color_mask = (False, False, False, False)
        fbo.use()  # moderngl applies a framebuffer's colour mask when it is bound
        try:
            self.kit.draw_depth()
        finally:
            fbo.color_mask = (True, True, True, True)
            fbo.use()
