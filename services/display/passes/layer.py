"""The static layer: the kit at rest and the floor drawn once per view, each frame only what
differs from it drawn again.

On llvmpipe (no GPU) a frame's cost is its shaded pixels, and most of them are the floor and
the kit, most of whose pieces are at rest in any frame. So the layer draws the kit at rest into
a colour and depth framebuffer of its own, lit and shadowed by the kit at rest (a shadow map of
its own, no drummer in it), whenever the view changes (camera, lights, background, the floor's
cell, the size), and each frame starts from a copy of it (a blit of colour and depth). Then:

* where the frame can differ from the copy, it is drawn again from scratch (cleared to the
  background, the whole kit in its current pose, with the frame's full shadow map), in whole
  tiles (:func:`livedrummer.render.shadow_region.tile_cover`): the old and the new pixels of
  every piece away from its rest pose (a swing, a lift, a pedal, a struck head's glow: boxes
  projected), and every tile whose still surfaces look up shadow-map texels that a caster not
  in the cache covers. Those casters (the drummer, the sticks, the moved pieces in both poses)
  are drawn depth-only from the key light at the map's resolution and read back (1 MB); the
  covered texels, grown by what a lookup reaches, are matched against a per-view table of the
  (tile, map cell) pairs the layer's surfaces look up (its depth read back and unprojected once
  per view). Where no moving caster covers a texel, the frame's map and the layer's hold the
  same depth there, so an untouched tile's shadows are the layer's;
* the drummer and the sticks, over everything, depth-tested against the copied depth.

Same shaders, same uniforms, so the same pixels as the full path:
``tests/services/display/test_render_layer.py`` compares the two frame for frame. The floor is
blended; in the full path it is drawn after the drummer, here before it. Both give the nearer
surface where the drummer stands in front of the floor, and nothing is ever below it. Limits: only
for the renderer's own off-screen target, without multisampling, when it clears the frame, not for
the kit drawn as an occluder only, and not for an avatar with transparent (BLEND) parts, whose
blending depends on draw order: the renderer takes the full path there; and while the view changes
every frame (a camera move): the layer is rebuilt once the view has held for two frames
(:meth:`LayerPass.still`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.background import Background
from livedrummer.render.kitmesh import INSTANCE_FLOATS, KitMesh
from livedrummer.render.scene import SceneFrame, empty_channels
from livedrummer.render.shadow_region import TILE_PX, Rect, box_corners, box_rects, tile_cover

from .backdrop import BackdropPass
from .body import BodyDraw
from .gpu import Gpu
from .kit import KIT_LAYOUT, KitDraw
from .post import PostPass
from .scene import FrameView
from .shadow import SHADOW_SIZE, SHADOW_UNIT, ShadowPass

#: shadow-map texels a lookup reaches round its surface point: the normal offset (12 mm, under
#: 3 texels where the map is finest) and the four filtered taps (2 texels), with margin
LOOKUP_REACH_TEXELS = 6
#: shadow-map texels a side of a cell of the per-view lookup table
CELL_TEXELS = 4
#: pixels round a changed pixel whose FXAA result may change (its taps reach 5 pixels out)
FXAA_REACH_PX = 6


class LayerPass:
    """The cached kit at rest and the per-frame redraw over it (see the module docstring)."""

    def __init__(self, gpu: Gpu, kit: KitDraw, size: tuple[int, int]) -> None:
        import moderngl

        self._gpu = gpu
        self._kit = kit
        ctx = gpu.ctx
        km: KitMesh = kit.kit_mesh
        self._kit_mesh = km
        self._rest = km.instances(empty_channels(km.pieces))
        lo_hi = {
            n: (m.vertices[:, :3].min(0), m.vertices[:, :3].max(0)) for n, m in gpu.meshes.items()
        }
        unit_lo = np.array([lo_hi[str(n)][0] for n in km.mesh]).reshape(-1, 3)
        unit_hi = np.array([lo_hi[str(n)][1] for n in km.mesh]).reshape(-1, 3)
        self._unit_corners = box_corners(unit_lo, unit_hi)  # (N, 8, 3) in each piece's frame
        self._casts = km.mesh != "floor"
        w, h = size
        self._colour = ctx.texture((w, h), 4)
        self._fbo = ctx.framebuffer(
            color_attachments=[self._colour], depth_attachment=ctx.depth_renderbuffer((w, h))
        )
        self._map = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
        self._map.compare_func = "<="
        self._map.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._map.repeat_x = self._map.repeat_y = False
        self._map_fbo = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer((SHADOW_SIZE, SHADOW_SIZE), 1)],
            depth_attachment=self._map,
        )
        # the moved casters drawn depth-only from the key light, at the shadow map's resolution
        self._moved_map = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer((SHADOW_SIZE, SHADOW_SIZE), 1)],
            depth_attachment=ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE)),
        )
        self._moved_draws: list[tuple[np.ndarray, Any, Any]] = []  # rows, buffer, depth vao
        for name, idx in kit.groups.items():
            if name != "floor":
                buf = ctx.buffer(reserve=2 * len(idx) * INSTANCE_FLOATS * 4, dynamic=True)
                self._moved_draws.append((idx, buf, gpu.vao("depth_mesh", name, buf, *KIT_LAYOUT)))
        # per view: which shadow-map cells each screen tile's still surfaces look up
        self._pair_tile = np.zeros(0, np.int64)
        self._pair_cell = np.zeros(0, np.int64)
        self._key: bytes | None = None  # the view the layer holds
        self._seen: bytes | None = None  # the view of the frame before
        #: rectangles redrawn in the last frame (for the bench and the tests)
        self.last_rects: list[Rect] = []
        #: rectangles outside which the last frame's pixels are the layer's, grown by what FXAA
        #: reads round a pixel (:attr:`PostPass.reuse`)
        self.changed: list[Rect] = []
        self._still_aa: Any = None  # the layer anti-aliased, made with the first FXAA frame

    def still(self, key: bytes) -> bool:
        """Whether to draw a frame of view ``key`` from the layer: when the layer holds it, or
        the frame before had it too (the view held still; the layer is rebuilt for it). A view
        that changes every frame (a camera move) takes the full path: rebuilding the layer each
        frame would cost more than it saves."""
        seen, self._seen = self._seen, key
        return key == self._key or key == seen

    def draw(
        self,
        fbo: Any,
        view: FrameView,
        key: bytes,
        frame: SceneFrame | None,
        inst: np.ndarray,
        body: BodyDraw,
        shadow: ShadowPass,
        background: Background,
        backdrop: BackdropPass,
        size: tuple[int, int],
        post: PostPass,
    ) -> None:
        """The frame into ``fbo`` (the renderer's own target): the layer (rebuilt when ``key``
        changed), the rectangles that differ from it, the drummer. The kit's buffers hold this
        frame's instances ``inst`` and the shadow pass has drawn this frame's map."""
        ctx = self._gpu.ctx
        if key != self._key:
            self._build(view, shadow.enabled, inst, background, backdrop, size)
            self._key = key
            if shadow.enabled:
                self._lookups(view, size)
            if post.fxaa:
                if self._still_aa is None:
                    tex = ctx.texture(size, 4)
                    self._still_aa = ctx.framebuffer(color_attachments=[tex])
                post.antialias(self._colour, self._still_aa)
        self.last_rects, drummer = self._rects(view, frame, inst, body, shadow.enabled, size)
        ctx.copy_framebuffer(fbo, self._fbo)
        fbo.use()
        ctx.viewport = (0, 0, *size)
        shadow.bind()
        grown = np.array(
            [
                (x - FXAA_REACH_PX, y - FXAA_REACH_PX, x + w + FXAA_REACH_PX, y + h + FXAA_REACH_PX)
                for x, y, w, h in self.last_rects
            ],
            np.int64,
        ).reshape(-1, 4)
        grown = np.concatenate([grown, drummer + np.array([-1, -1, 1, 1]) * FXAA_REACH_PX])
        grown[:, [0, 2]] = grown[:, [0, 2]].clip(0, size[0])
        grown[:, [1, 3]] = grown[:, [1, 3]].clip(0, size[1])
        self.changed = tile_cover(grown, size)
        post.reuse = (self._still_aa, self.changed) if post.fxaa else None
        for rect in self.last_rects:
            ctx.scissor = rect
            self._clear(background, backdrop, size)
        ctx.scissor = None
        # the drummer before the kit, as in the full path, so that equal depths (a stick on a
        # head, a shoe on a pedal) resolve the same way inside the rectangles
        body.draw(fbo)
        if self.last_rects:
            # the pieces in one draw over the rectangles' box: outside the cleared rectangles
            # every fragment meets the copied depth of the same surface (or the drummer's,
            # nearer) and fails the early depth test; the floor once in each rectangle, as its
            # shader discards (a stage's cell) and so is depth-tested late, after shading
            r = np.array(self.last_rects)
            x0, y0 = r[:, 0].min(), r[:, 1].min()
            x1, y1 = (r[:, 0] + r[:, 2]).max(), (r[:, 1] + r[:, 3]).max()
            ctx.scissor = (int(x0), int(y0), int(x1 - x0), int(y1 - y0))
            self._kit.draw_pieces()
            ctx.scissor = None
            self._kit.draw_floor(ctx, self.last_rects)

    def _build(
        self,
        view: FrameView,
        shadows: bool,
        inst: np.ndarray,
        background: Background,
        backdrop: BackdropPass,
        size: tuple[int, int],
    ) -> None:
        """The kit at rest, shadowed by itself alone, into the layer."""
        ctx = self._gpu.ctx
        self._kit.upload(self._rest)
        if shadows:
            self._gpu.programs["depth_mesh"]["u_view_proj"].write(view.light_vp.T.tobytes())
            self._map_fbo.use()
            ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
            self._map_fbo.clear(depth=1.0)
            self._kit.draw_depth()
            self._map.use(location=SHADOW_UNIT)
        self._fbo.use()
        ctx.viewport = (0, 0, *size)
        self._clear(background, backdrop, size)
        self._kit.draw(ctx)
        self._kit.upload(inst)

    def _clear(self, background: Background, backdrop: BackdropPass, size: tuple[int, int]) -> None:
        """The bound framebuffer (within the scissor, if set) cleared to the background."""
        import moderngl

        ctx = self._gpu.ctx
        ctx.fbo.clear(*background.rgb, background.alpha, depth=1.0)
        if background.image is not None:
            backdrop.draw(background.image, size)
        ctx.enable(moderngl.DEPTH_TEST)

    def _rects(
        self,
        view: FrameView,
        frame: SceneFrame | None,
        inst: np.ndarray,
        body: BodyDraw,
        shadows: bool,
        size: tuple[int, int],
    ) -> tuple[list[Rect], np.ndarray]:
        """Where this frame's kit can differ from the layer (see the module docstring), as
        tiles; and the drummer's pixel boxes (B, 4: x0, y0, x1, y1)."""
        moved = np.flatnonzero((inst != self._rest).any(axis=1))
        worlds = [self._world_corners(self._rest, moved), self._world_corners(inst, moved)]
        own = box_rects(np.concatenate(worlds), view.view_proj, size)
        rects = [own]
        drummer = np.zeros((0, 4), np.int64)
        if frame is not None:
            d_lo, d_hi = body.caster_boxes(frame, 0.0)
            drummer = box_rects(box_corners(d_lo, d_hi), view.view_proj, size)
        if shadows:
            rects.append(self._shadowed_tiles(moved, inst, body, frame, size))
        return tile_cover(np.concatenate(rects), size), drummer

    def _lookups(self, view: FrameView, size: tuple[int, int]) -> None:
        """For the view just built: every (screen tile, shadow-map cell) pair where a still
        surface of the layer looks the map up (its depth read back, unprojected, seen from the
        key light)."""
        w, h = size
        depth = np.frombuffer(
            self._fbo.read(components=1, attachment=-1, dtype="f4"), np.float32
        ).reshape(h, w)
        ys, xs = np.nonzero(depth < 1.0)
        z = depth[ys, xs].astype(np.float64) * 2 - 1
        ndc = np.stack(
            [(xs + 0.5) / w * 2 - 1, (ys + 0.5) / h * 2 - 1, z, np.ones(len(xs))], axis=1
        )
        world = ndc @ np.linalg.inv(view.view_proj.astype(np.float64)).T
        world /= world[:, 3:4]
        light = world @ view.light_vp.astype(np.float64).T
        keep = light[:, 3] > 1e-6
        uv = light[keep, :2] / light[keep, 3:4] * 0.5 + 0.5
        inside = (np.abs(uv - 0.5) < 0.55).all(axis=1)  # beyond the map: lit, never shadowed
        texel = np.clip((uv[inside] * SHADOW_SIZE).astype(np.int64), 0, SHADOW_SIZE - 1)
        cells = SHADOW_SIZE // CELL_TEXELS
        cell = (texel[:, 1] // CELL_TEXELS) * cells + texel[:, 0] // CELL_TEXELS
        cols = -(-w // TILE_PX)
        tile = ((ys[keep][inside] // TILE_PX) * cols + xs[keep][inside] // TILE_PX).astype(np.int64)
        pairs = np.unique(tile * cells * cells + cell)
        self._pair_tile, self._pair_cell = pairs // (cells * cells), pairs % (cells * cells)

    def _shadowed_tiles(
        self,
        moved: np.ndarray,
        inst: np.ndarray,
        body: BodyDraw,
        frame: SceneFrame | None,
        size: tuple[int, int],
    ) -> np.ndarray:
        """Pixel boxes (T, 4) of the tiles whose still surfaces look up shadow-map texels that
        this frame's moving casters cover (or the moved pieces covered at rest): the drummer,
        the sticks and the moved pieces in both poses drawn depth-only at the map's resolution
        (the depth programs hold the key light's view already), read back, and grown by what
        a lookup reaches (the normal offset and the filter's taps)."""
        import moderngl

        ctx = self._gpu.ctx
        self._moved_map.use()
        ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
        ctx.enable(moderngl.DEPTH_TEST)
        self._moved_map.clear(depth=1.0)
        moving = set(moved[self._casts[moved]].tolist())
        for idx, buf, vao in self._moved_draws:
            rows = idx[[i in moving for i in idx]] if moving else idx[:0]
            if len(rows):
                buf.write(np.concatenate([self._rest[rows], inst[rows]]).tobytes())
                vao.render(instances=2 * len(rows))
        if frame is not None:
            body.draw_depth()
        texels = (
            np.frombuffer(
                self._moved_map.read(components=1, attachment=-1, dtype="f4"), np.float32
            ).reshape(SHADOW_SIZE, SHADOW_SIZE)
            < 1.0
        )
        if not texels.any():
            return np.zeros((0, 4), np.int64)
        grown = texels.copy()
        for axis in (0, 1):
            step = grown.copy()
            for d in range(1, LOOKUP_REACH_TEXELS + 1):
                step |= np.roll(grown, d, axis=axis) | np.roll(grown, -d, axis=axis)
            grown = step
        cells = SHADOW_SIZE // CELL_TEXELS
        marked = grown.reshape(cells, CELL_TEXELS, cells, CELL_TEXELS).any(axis=(1, 3)).ravel()
        tiles = np.unique(self._pair_tile[marked[self._pair_cell]])
        cols = -(-size[0] // TILE_PX)
        x0, y0 = (tiles % cols) * TILE_PX, (tiles // cols) * TILE_PX
        return np.stack([x0, y0, x0 + TILE_PX, y0 + TILE_PX], axis=1).clip(0, [*size, *size])

    def _world_corners(self, inst: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The world corners (R, 8, 3) of the unit-mesh boxes of ``inst``'s ``rows``."""
        model = inst[rows, :16].reshape(-1, 4, 4).transpose(0, 2, 1).astype(np.float64)
        local = self._unit_corners[rows]
        out: np.ndarray = np.einsum("rij,rkj->rki", model[:, :3, :3], local) + model[:, None, :3, 3]
        return out
