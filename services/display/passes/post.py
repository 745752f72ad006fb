"""The post pass: the off-screen targets, the multisample resolve and the FXAA pass.

Off screen, the scene is drawn into :attr:`PostPass.fbo`: a texture framebuffer, or with
``samples > 0`` a multisampled one resolved into it (multisampling costs about 2.7x on
llvmpipe). With ``fxaa`` a full-screen anti-aliasing pass (``shaders/fxaa.frag``) runs once
over the drawn scene into a texture of its own, before the first read-back or overlay
(:meth:`PostPass.resolved`, lazily: a frame drawn and never read costs no resolve). The
result is :attr:`PostPass.final` and its colour texture :attr:`PostPass.final_tex`. A window's
renderer has no post pass targets (its framebuffer is the screen). Limits: FXAA off screen
only; overlays painted after it are not filtered.
"""

from __future__ import annotations

from typing import Any

from livedrummer.render.shaders import shader_source


class PostPass:
    """Targets and resolve of one renderer (see the module docstring)."""

    def __init__(
        self, ctx: Any, size: tuple[int, int], *, offscreen: bool, samples: int, fxaa: bool
    ) -> None:
        import moderngl

        self._ctx = ctx
        self.samples = samples
        self.fxaa = fxaa and offscreen
        self.fbo: Any = None  # what the scene is drawn into
        self._resolve: Any = None
        colour: Any = None
        if offscreen:
            w, h = size
            colour = ctx.texture((w, h), 4)
            colour.filter = (moderngl.LINEAR, moderngl.LINEAR)
            plain = ctx.framebuffer(color_attachments=[colour])
            if samples > 0:
                rb = ctx.renderbuffer((w, h), 4, samples=samples)
                depth = ctx.depth_renderbuffer((w, h), samples=samples)
                self.fbo = ctx.framebuffer(color_attachments=[rb], depth_attachment=depth)
                self._resolve = plain
            else:
                depth = ctx.depth_renderbuffer((w, h))
                self.fbo = ctx.framebuffer(color_attachments=[colour], depth_attachment=depth)
                self._resolve = self.fbo
        #: the finished frame's framebuffer and its colour texture
        self.final: Any = self._resolve
        self.final_tex: Any = colour
        self._fxaa: Any = None  # the FXAA pass's vertex array
        self._scene_tex: Any = colour
        self._samplers: dict[int, Any] = {}
        #: a frame drawn since the anti-aliasing pass last ran
        self.stale = False
        #: set by a static layer for the frame drawn last: a framebuffer holding its still
        #: picture anti-aliased already, and the rectangles outside which the frame's filtered
        #: pixels equal it (FXAA reads a few pixels round each; the layer grows them by that)
        self.reuse: tuple[Any, list[tuple[int, int, int, int]]] | None = None
        if self.fxaa:
            post = ctx.texture(size, 4)
            self.final, self.final_tex = ctx.framebuffer(color_attachments=[post]), post
            prog = ctx.program(
                vertex_shader=shader_source("fullscreen.vert"),
                fragment_shader=shader_source("fxaa.frag"),
            )
            prog["u_image"].value = 0
            self._fxaa = ctx.vertex_array(prog, [])

    def overlay_target(self, target: Any) -> Any:
        """The framebuffer an overlay is painted into: ``target``, else the off-screen frame,
        after the anti-aliasing pass when there is one (overlays go over it as painted)."""
        if target is None and self._fxaa is not None:
            self.resolved()
            return self.final
        self.stale = True
        return target if target is not None else self.fbo

    def resolved(self) -> None:
        """The frame drawn since the last call resolved (multisampling) and anti-aliased (FXAA)
        into :attr:`final`; nothing to do when nothing was drawn since."""
        if not self.stale:
            return
        ctx = self._ctx
        if self.samples > 0:
            ctx.copy_framebuffer(self._resolve, self.fbo)
        if self._fxaa is not None:
            if self.reuse is not None:
                still, rects = self.reuse
                ctx.copy_framebuffer(self.final, still)
                self.antialias(self._scene_tex, self.final, rects)
            else:
                self.antialias(self._scene_tex, self.final)
        self.stale = False

    def antialias(
        self, texture: Any, target: Any, rects: list[tuple[int, int, int, int]] | None = None
    ) -> None:
        """The FXAA pass over ``texture`` into framebuffer ``target`` of the same size, over the
        whole frame or only within ``rects`` (x, y, w, h from the bottom left)."""
        import moderngl

        if self._fxaa is None:
            raise ValueError("antialias on a renderer without FXAA")
        ctx = self._ctx
        vao = self._fxaa
        sampler = self._samplers.get(id(texture))
        if sampler is None:
            sampler = ctx.sampler(
                texture=texture,
                filter=(moderngl.LINEAR, moderngl.LINEAR),
                repeat_x=False,
                repeat_y=False,
            )
            self._samplers[id(texture)] = sampler
        target.use()
        w, h = texture.size
        ctx.viewport = (0, 0, w, h)
        ctx.disable(moderngl.DEPTH_TEST)
        vao.program["u_texel"].value = (1.0 / w, 1.0 / h)
        sampler.use(location=0)
        for rect in [None] if rects is None else rects:
            ctx.scissor = rect
            vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.scissor = None
        sampler.clear(location=0)
