"""The overlay pass: a 2D RGBA image blended over the frame drawn last.

The score and joint-angle strips (:mod:`livedrummer.render.overlay_raster`), a HUD, a practice
panel: straight alpha, top row first, at a rectangle in pixels from the frame's top-left corner
(``shaders/overlay.frag``). The texture is made once per image size and rewritten each call;
it is sampled nearest, pixel for pixel. Limits: one image a call; no scaling.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.shaders import shader_source


def overlay_drawn(image: np.ndarray, rect: tuple[int, int, int, int]) -> bool:
    """Whether ``image`` at ``rect`` draws anything: False for an empty rectangle; a rectangle
    that is not the image's size is a ValueError."""
    h_img, w_img = image.shape[:2]
    w, h = rect[2:]
    if (w_img, h_img) != (w, h):
        raise ValueError(f"overlay image is {w_img}x{h_img}, its rectangle {w}x{h}")
    return w > 0 and h > 0


class OverlayPass:
    """The overlay's program and texture, made on first use."""

    def __init__(self, ctx: Any) -> None:
        self._ctx = ctx
        self._vao: Any = None
        self._tex: Any = None

    def draw(
        self,
        image: np.ndarray,
        rect: tuple[int, int, int, int],
        fbo: Any,
        frame_size: tuple[int, int],
    ) -> None:
        """Blend ``image`` ((h, w, 4) uint8) at ``rect`` = (x, y, w, h) into ``fbo``, a frame of
        ``frame_size`` (see :func:`overlay_drawn`)."""
        import moderngl

        if not overlay_drawn(image, rect):
            return
        ctx = self._ctx
        x, y, w, h = rect
        if self._vao is None:
            prog = ctx.program(
                vertex_shader=shader_source("fullscreen.vert"),
                fragment_shader=shader_source("overlay.frag"),
            )
            prog["u_image"].value = 0
            self._vao = ctx.vertex_array(prog, [])
        if self._tex is None or self._tex.size != (w, h):
            if self._tex is not None:
                self._tex.release()
            self._tex = ctx.texture((w, h), 4)
            self._tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._tex.repeat_x = self._tex.repeat_y = False
        self._tex.write(np.ascontiguousarray(image, np.uint8))
        fbo.use()
        bottom = frame_size[1] - y - h  # GL rows count from the bottom
        ctx.viewport = (x, bottom, w, h)
        self._vao.program["u_rect"].value = (float(x), float(bottom), float(w), float(h))
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (
            moderngl.SRC_ALPHA,
            moderngl.ONE_MINUS_SRC_ALPHA,
            moderngl.ZERO,
            moderngl.ONE,
        )
        self._tex.use(location=0)
        self._vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.disable(moderngl.BLEND)
        ctx.viewport = (0, 0, *frame_size)
