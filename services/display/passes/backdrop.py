"""The backdrop pass: an image background stretched over the whole cleared frame.

``overlay.frag`` with the frame as its rectangle, depth neither tested nor written, so the
scene draws over it; the texture is made once, from the first image drawn (a renderer's
:class:`~livedrummer.render.background.Background` does not change). Limits: stretched, not
fitted; no mipmaps (a far larger image than the frame aliases).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.shaders import shader_source


class BackdropPass:
    """The background image's texture and full-screen draw, made on first use."""

    def __init__(self, ctx: Any) -> None:
        self._ctx = ctx
        self._made: tuple[Any, Any] | None = None

    def draw(self, image: np.ndarray, size: tuple[int, int]) -> None:
        """Stretch ``image`` ((H, W, 3) uint8, top row first) over a frame of ``size``."""
        import moderngl

        ctx = self._ctx
        if self._made is None:
            prog = ctx.program(
                vertex_shader=shader_source("fullscreen.vert"),
                fragment_shader=shader_source("overlay.frag"),
            )
            prog["u_image"].value = 0
            h, w = image.shape[:2]
            rgba = np.dstack([image, np.full((h, w), 255, np.uint8)])
            tex = ctx.texture((w, h), 4, np.ascontiguousarray(rgba).tobytes())
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            self._made = (ctx.vertex_array(prog, []), tex)
        vao, tex = self._made
        w, h = size
        vao.program["u_rect"].value = (0.0, 0.0, float(w), float(h))
        ctx.disable(moderngl.DEPTH_TEST)
        tex.use(location=0)
        vao.render(moderngl.TRIANGLES, vertices=3)
