"""The renderer: one kit, one drummer and the sticks, drawn as a sequence of passes.

A thin composition of the passes in :mod:`services.display.passes`, each owning its own GL
state, in the way pygfx keeps the scene (plain data: :class:`KitMesh`, :class:`SceneFrame`,
:class:`LightRig`, :class:`Camera`) apart from the renderer that maps it to the GPU. A frame is:
clear to the ``background`` (:mod:`livedrummer.render.background`: the dark hall, a colour,
chroma green, alpha 0, or an image stretched over it first by :class:`BackdropPass`), upload the
frame's kit channels, joints and sticks into the instance buffers (:class:`ScenePass`), draw the
casters into the key light's shadow map (:class:`ShadowPass`, ``shadows``, on by default), draw
the body and the kit lit and shadowed (:class:`ScenePass`), or, for the renderer's own
off-screen frame, start from the kit at rest cached per view and draw only what differs from
it (:class:`LayerPass`, ``static_layer``, on by default: the same pixels, fewer of them
shaded; with FXAA, the same frame twice in a row is drawn once); then, when asked, an overlay
(:meth:`Renderer.draw_overlay`, :class:`OverlayPass`), the resolve and FXAA (:class:`PostPass`)
and a read-back (:class:`ReadbackPass`: :meth:`Renderer.read_rgb`, :meth:`Renderer.read_rgba`,
:meth:`Renderer.read_i420`).

The drummer is a skinned avatar (``avatar``; by default the built-in character of
:func:`livedrummer.avatar.character.build_character`) posed on the GPU (:mod:`.avatar_gl`), or,
with ``avatar="mannequin"`` or for a frame without rotations or a skeleton other than the body's
24 joints, a capsule mannequin (:mod:`.passes.body`). Built once per (context, kit, skeleton,
size): unit meshes are uploaded once; per frame only the instance buffers change. A window
either draws off screen and copies the frame in (:meth:`Renderer.present`, the live window),
or passes its framebuffer to :meth:`Renderer.draw` and sets :attr:`Renderer.size` when it is
resized. Limits: one shadowed light; the kit's surfaces are opaque (the avatar's BLEND parts
cast no shadow); every surface is lit by the same rig.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.render.background import HALL, Background
from livedrummer.render.camera import Camera
from livedrummer.render.kitmesh import KitMesh
from livedrummer.render.lights import DEFAULT_LOOK, LightRig, look_rig
from livedrummer.render.scene import SceneFrame, Skeleton

from .avatar_gl import SkinnedDraw
from .passes.backdrop import BackdropPass
from .passes.body import PALETTE, STICK_COLOR, STICK_RADIUS_M
from .passes.gpu import Gpu
from .passes.layer import LayerPass
from .passes.overlay import OverlayPass, overlay_drawn
from .passes.post import PostPass
from .passes.readback import ReadbackPass, i420_ok
from .passes.scene import MAX_CELL_OTHERS, FrameView, ScenePass
from .passes.shadow import SHADOW_SIZE, ShadowPass, key_light_view_projection

__all__ = [
    "BACKGROUND",
    "MAX_CELL_OTHERS",
    "PALETTE",
    "SHADOW_SIZE",
    "STICK_COLOR",
    "STICK_RADIUS_M",
    "Renderer",
    "i420_ok",
    "key_light_view_projection",
]

BACKGROUND = HALL


def _frame_bytes(frame: SceneFrame | None) -> bytes:
    """What a frame's pixels depend on, as bytes (its time too: the face's weights follow it)."""
    if frame is None:
        return b""
    rot = frame.rotations_q
    parts = [
        frame.joints_m,
        frame.sticks_m,
        frame.channels,
        np.float64(frame.time_s),
        np.zeros(0, np.float32) if rot is None else rot,
    ]
    return b"|".join(np.ascontiguousarray(p).tobytes() for p in parts) + bytes([rot is None])


class Renderer:
    """Draws one kit and one skeleton; see the module docstring."""

    def __init__(
        self,
        ctx: Any,
        kit_mesh: KitMesh,
        skeleton: Skeleton | None,
        size: tuple[int, int],
        *,
        samples: int = 4,
        offscreen: bool = True,
        avatar: Avatar | Literal["mannequin"] | None = None,
        shadows: bool = True,
        background: Background | None = None,
        fxaa: bool = False,
        kit_occludes_only: bool = False,
        cache_static_shadow: bool = True,
        lights: LightRig | None = None,
        static_layer: bool = True,
    ) -> None:
        self.ctx = ctx
        #: the show lights (:mod:`livedrummer.render.lights`); replace it to relight the next
        #: frame (a live OSC or cue change)
        self.lights = lights if lights is not None else look_rig(DEFAULT_LOOK)
        #: the kit drawn into depth only, before the body: the body alone is seen, hidden where
        #: the kit is in front of it (a practice teacher's ghost, :mod:`.practice_view`)
        self.kit_occludes_only = kit_occludes_only
        self.background = background if background is not None else Background()
        #: the frame's size in pixels; a window sets it when its framebuffer is resized
        self.size = size
        #: the other drummers' pool centres on a stage, in this kit's frame: the floor is drawn
        #: only nearer to its own (``shaders/floor_cell.glsl``); empty for one drummer
        self.floor_cell_others = np.zeros((0, 2), np.float32)
        self.gpu = Gpu(ctx)
        self.scene = ScenePass(self.gpu, kit_mesh, skeleton, avatar)
        self.shadow = ShadowPass(
            self.gpu, self.scene.kit, enabled=shadows, cache_static=cache_static_shadow
        )
        self.post = PostPass(ctx, size, offscreen=offscreen, samples=samples, fxaa=fxaa)
        self.backdrop = BackdropPass(ctx)
        self.overlay = OverlayPass(ctx)
        self.readback = ReadbackPass(ctx, self.post)
        self._inst = np.zeros((0, 0), np.float32)  # the kit's instances uploaded last
        #: the still kit cached per view (:mod:`.passes.layer`); None where it cannot apply
        self.layer: LayerPass | None = None
        #: the view key and the frame the layer drew last. With FXAA, overlays go over the
        #: filtered copy, never into the scene's target, so the same frame again (an idle
        #: show's kit at rest, a paused pose) is not drawn again: the target holds it still and
        #: the next read-back or present filters it afresh, as for the frame drawn last.
        self._held: tuple[bytes, bytes] | None = None
        body = self.scene.body
        if (
            static_layer
            and self.post.fbo is not None
            and samples == 0
            and not kit_occludes_only
            and not body.has_blend
        ):
            self.layer = LayerPass(self.gpu, self.scene.kit, size)

    # what the users of the renderer (and its tests) read of its parts
    @property
    def kit_mesh(self) -> KitMesh:
        return self.scene.kit_mesh

    @property
    def skeleton(self) -> Skeleton | None:
        return self.scene.body.skeleton

    @property
    def programs(self) -> dict[str, Any]:
        return self.gpu.programs

    @property
    def skinned(self) -> SkinnedDraw | None:
        return self.scene.body.skinned

    @property
    def shadows(self) -> bool:
        return self.shadow.enabled

    @property
    def cache_static_shadow(self) -> bool:
        return self.shadow.cache_static

    @property
    def samples(self) -> int:
        return self.post.samples

    @property
    def fxaa(self) -> bool:
        return self.post.fxaa

    @property
    def _shadow_map(self) -> Any:
        return self.shadow.map

    @property
    def _fbo(self) -> Any:
        return self.post.fbo

    def upload(self, frame: SceneFrame | None) -> None:
        """Copy one frame's kit channels, joints and sticks into the instance buffers."""
        self._inst = self.scene.upload(frame)
        self.shadow.upload(self._inst)

    def draw(
        self, frame: SceneFrame | None, camera: Camera, target: Any = None, clear: bool = True
    ) -> None:
        """Draw ``frame`` (None: the kit at rest and no drummer) seen from ``camera``;
        ``clear=False`` draws over what ``target`` holds, depth-tested (a stage's drummers)."""
        import moderngl

        ctx = self.ctx
        fbo = target if target is not None else self.post.fbo
        self.post.stale = True
        fbo.use()
        w, h = self.size
        ctx.viewport = (0, 0, w, h)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        view = self.scene.frame(camera, w / h, self.lights, self.shadow.enabled)
        layer = self.layer if target is None and clear and not self.kit_occludes_only else None
        key = self._layer_key(view) if layer is not None else b""
        if layer is not None and layer.still(key):
            held = (key, _frame_bytes(frame))
            if held == self._held and self.post.fxaa and self.post.reuse is not None:
                return  # the same picture: the scene is in the target still (see _held)
            self._held = held
            self.upload(frame)
            self.scene.floor_cell(self.floor_cell_others)
            self.gpu.set_uniforms(view.uniforms)
            if self.shadow.enabled:
                self.shadow.draw(view.light_vp, self.scene.kit, self.scene.body)
            layer.draw(
                fbo,
                view,
                key,
                frame,
                self._inst,
                self.scene.body,
                self.shadow,
                self.background,
                self.backdrop,
                self.size,
                self.post,
            )
            return
        self.post.reuse = None
        self._held = None
        if clear:
            bg = self.background
            fbo.clear(*bg.rgb, bg.alpha, depth=1.0)
            if bg.image is not None:
                self.backdrop.draw(bg.image, self.size)
                ctx.enable(moderngl.DEPTH_TEST)
        self.upload(frame)
        self.scene.floor_cell(self.floor_cell_others)
        self.gpu.set_uniforms(view.uniforms)
        if self.shadow.enabled:
            self.shadow.draw(view.light_vp, self.scene.kit, self.scene.body)
            fbo.use()
            ctx.viewport = (0, 0, w, h)
        self.shadow.bind()
        self.scene.draw(fbo, view, self.kit_occludes_only)

    def _layer_key(self, view: FrameView) -> bytes:
        """What the static layer's pixels depend on: the view's uniforms (camera, lights), the
        floor's cell, the background and the size."""
        bg = self.background
        parts = [
            repr(sorted((k, v) for k, v in view.uniforms.items())).encode(),
            np.asarray(self.floor_cell_others, np.float32).tobytes(),
            repr((bg.kind, bg.rgb, bg.path, id(bg.image), self.size)).encode(),
        ]
        return b"|".join(parts)

    def pool_centre(self) -> np.ndarray:
        """The centre (x, y) of the floor's pool of key light, in this kit's frame."""
        return np.asarray(self.scene.centre()[:2], float)

    def draw_overlay(
        self, image: np.ndarray, rect: tuple[int, int, int, int], target: Any = None
    ) -> None:
        """Blend ``image`` ((h, w, 4) uint8, straight alpha, top row first) over the frame
        drawn last, at ``rect`` = (x, y, w, h) in pixels from the frame's top-left corner.

        Same target as :meth:`draw` (the off-screen frame by default), so the read-backs
        include it. The texture is made once per image size and rewritten each call."""
        if overlay_drawn(image, rect):
            self.overlay.draw(image, rect, self.post.overlay_target(target), self.size)

    def read_rgb(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 3) uint8, top row first."""
        return self.readback.rgb(self.size)

    def read_rgba(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 4) uint8, bottom row first (GL order).

        The driver's native layout: the fastest read-back; the encoder flips it for free.
        """
        return self.readback.rgba(self.size)

    def read_rgba_top(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 4) uint8 with its alpha, top row first (PNG)."""
        return np.ascontiguousarray(self.read_rgba()[::-1])

    def read_i420(self) -> np.ndarray:
        """The last off-screen frame as I420, (H*3/2, W) uint8, top row first (see
        :meth:`ReadbackPass.i420`); W must be a multiple of 8 (:func:`i420_ok`)."""
        return self.readback.i420(self.size)

    def present(self, target: Any) -> None:
        """Copy the finished off-screen frame (resolved, anti-aliased, with its overlays) into
        ``target`` of the same size: one blit, e.g. into a window's framebuffer, so a window
        can draw through the static layer (:mod:`.passes.layer`), which needs the renderer's
        own target."""
        if self.post.fbo is None:
            raise ValueError("present on a renderer drawing into a window's framebuffer")
        self.post.resolved()
        self.ctx.copy_framebuffer(target, self.post.final)

    def finish(self) -> None:
        self.ctx.finish()
