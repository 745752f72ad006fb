"""The shadow pass: every caster depth-only from the key spot into a square depth texture.

The casters are the kit's pieces, the drummer and the sticks (not the floor); every lit surface
and the floor look the map up with a hardware-compared 2x2 filter (``shaders/shadow.glsl``),
bound at :data:`SHADOW_UNIT`. With ``cache_static_shadow`` the kit's parts that never move
(``MOTION_STATIC``) are drawn once per key light into a map of their own, which each frame
starts from (a depth blit), and only the drummer, the sticks and the parts that may move are
drawn over it: the same depths, the nearest of all casters at every texel in whatever order
drawn. Limits: one shadowed light; a sphere of :data:`SHADOW_RADIUS_M` round the kit.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.camera import look_at, perspective
from livedrummer.render.kitmesh import INSTANCE_FLOATS, MOTION_STATIC, KitMesh
from livedrummer.render.scene import empty_channels

from .body import BodyDraw
from .gpu import Gpu
from .kit import KIT_LAYOUT, KitDraw

SHADOW_SIZE = 512  # texels a side: ~7 mm at the kit, from the key light 4.6 m away
SHADOW_RADIUS_M = 1.8  # the sphere round the kit's centre that the shadow map covers
SHADOW_UNIT = 1  # texture unit of the shadow map (unit 0 is the avatar's base colour)
_DEPTH_PROGRAMS = ("depth_mesh", "depth_segment", "depth_ball", "depth_skin")


class ShadowPass:
    """The key light's shadow map and how it is drawn (see the module docstring)."""

    def __init__(self, gpu: Gpu, kit: KitDraw, *, enabled: bool, cache_static: bool) -> None:
        import moderngl

        self._gpu = gpu
        self.enabled = enabled
        ctx = gpu.ctx
        side = SHADOW_SIZE if enabled else 1
        self.map = ctx.depth_texture((side, side))
        self.map.compare_func = "<="
        self.map.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self.map.repeat_x = self.map.repeat_y = False
        # a colour attachment, never looked at: a blit copies depth only between framebuffers
        # that have one (Mesa)
        self._fbo = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer((side, side), 1)], depth_attachment=self.map
        )
        self.cache_static = cache_static and enabled
        self._static: list[tuple[Any, int]] = []
        self._moving: list[tuple[Any, Any, np.ndarray]] = []
        self._static_key: bytes | None = None  # the light the static map was drawn for
        self._static_fbo: Any = None
        if self.cache_static:
            self._cache_setup(kit, side)
        for prog in gpu.programs.values():
            if "u_shadow_map" in prog:
                prog["u_shadow_map"].value = SHADOW_UNIT

    def _cache_setup(self, kit: KitDraw, side: int) -> None:
        """The kit's casters split into those that never move (drawn once into
        ``_static_fbo`` per key light) and those that may (drawn each frame)."""
        km: KitMesh = kit.kit_mesh
        ctx = self._gpu.ctx
        moving = km.motion != MOTION_STATIC
        rest = km.instances(empty_channels(km.pieces))
        for name, idx in kit.groups.items():
            if name == "floor":
                continue
            still, move = idx[~moving[idx]], idx[moving[idx]]
            if len(still):
                buf = ctx.buffer(rest[still].tobytes())
                self._static.append(
                    (self._gpu.vao("depth_mesh", name, buf, *KIT_LAYOUT), len(still))
                )
            if len(move):
                buf = ctx.buffer(reserve=len(move) * INSTANCE_FLOATS * 4, dynamic=True)
                vao = self._gpu.vao("depth_mesh", name, buf, *KIT_LAYOUT)
                self._moving.append((vao, buf, move))
        depth = ctx.depth_texture((side, side))
        self._static_fbo = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer((side, side), 1)], depth_attachment=depth
        )

    def upload(self, inst: np.ndarray) -> None:
        """Write a frame's kit instances into the moving casters' buffers."""
        for _vao, buf, idx in self._moving:
            buf.write(inst[idx].tobytes())

    def draw(self, light_vp: np.ndarray, kit: KitDraw, body: BodyDraw) -> None:
        """Draw every caster depth-only from the key light (view-projection ``light_vp``)."""
        ctx = self._gpu.ctx
        vp = light_vp.T.tobytes()
        for name in _DEPTH_PROGRAMS:
            self._gpu.programs[name]["u_view_proj"].write(vp)
        if self.cache_static:
            if self._static_key != vp:
                self._static_fbo.use()
                ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
                self._static_fbo.clear(depth=1.0)
                for vao, count in self._static:
                    vao.render(instances=count)
                self._static_key = vp
            ctx.copy_framebuffer(self._fbo, self._static_fbo)
            self._fbo.use()
            ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
        else:
            self._fbo.use()
            ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
            self._fbo.clear(depth=1.0)
        body.draw_depth()
        if self.cache_static:
            for vao, _buf, idx in self._moving:
                vao.render(instances=len(idx))
            return
        kit.draw_depth()

    def bind(self) -> None:
        """The map onto its texture unit, for the lit passes to sample."""
        self.map.use(location=SHADOW_UNIT)


def key_light_view_projection(key: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The key spot's view-projection (row-major float32): from ``key`` at ``target``, a
    frustum just wide enough for a sphere of :data:`SHADOW_RADIUS_M` round the target."""
    dist = float(np.linalg.norm(target - key))
    fov = float(np.degrees(2.0 * np.arcsin(min(SHADOW_RADIUS_M / dist, 0.95))))
    near = max(dist - SHADOW_RADIUS_M - 0.5, 0.1)
    vp: np.ndarray = (
        perspective(fov, 1.0, near, dist + SHADOW_RADIUS_M + 0.5) @ look_at(key, target)
    ).astype(np.float32)
    return vp
