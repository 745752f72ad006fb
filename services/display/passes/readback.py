"""The read-back pass: the finished frame into numpy, as a PNG writer or an encoder wants it.

:meth:`ReadbackPass.rgba` is the driver's own bottom-up RGBA, the cheapest read-back (the
encoder flips it for free); :meth:`ReadbackPass.rgb` top-down RGB rows as PNG writers expect;
:meth:`ReadbackPass.i420` converts the frame to the video encoder's planar YUV 4:2:0 on the GPU
first (two full-screen passes, ``shaders/i420_*.frag``), so the encoder gets 1.5 bytes a pixel,
already top-down, and the CPU neither flips nor converts. Limits: I420 needs a width that is a
multiple of 8 and an even height (:func:`i420_ok`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.shaders import shader_source

from .post import PostPass


def i420_ok(size: tuple[int, int]) -> bool:
    """Whether :meth:`ReadbackPass.i420` can convert frames of ``size`` (W, H)."""
    return size[0] % 8 == 0 and size[1] % 2 == 0


class ReadbackPass:
    """Reads one renderer's :class:`PostPass` result (see the module docstring)."""

    def __init__(self, ctx: Any, post: PostPass) -> None:
        self._ctx = ctx
        self._post = post
        self._i420: tuple[list[tuple[Any, Any]], Any] | None = None  # made on first use

    def rgb(self, size: tuple[int, int]) -> np.ndarray:
        """(H, W, 3) uint8, top row first."""
        w, h = size
        self._post.resolved()
        data = self._post.final.read(components=3, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h, w, 3)[::-1]

    def rgba(self, size: tuple[int, int]) -> np.ndarray:
        """(H, W, 4) uint8, bottom row first (GL order)."""
        w, h = size
        self._post.resolved()
        data = self._post.final.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h, w, 4)

    def i420(self, size: tuple[int, int]) -> np.ndarray:
        """I420, (H*3/2, W) uint8, top row first.

        Rows ``[0, H)`` are the luma plane; the rest hold the Cb then the Cr plane, each
        (W/2) x (H/2) bytes laid end to end (BT.709, limited range; see ``shaders/bt709.glsl``).
        Two full-screen passes write it into an RGBA8 target W/4 wide, four bytes a fragment,
        whose read-back is the same bytes as a W-wide single-channel one.
        """
        import moderngl

        w, h = size
        if not i420_ok(size):
            raise ValueError(f"I420 read-back needs a width that is a multiple of 8, not {w}")
        self._post.resolved()
        if self._i420 is None:
            self._i420 = self._setup(size)
        passes, fbo = self._i420
        fbo.use()
        ctx = self._ctx
        ctx.disable(moderngl.DEPTH_TEST)
        for (vao, sampler), rows in zip(passes, ((0, h), (h, h // 2)), strict=True):
            sampler.use(location=0)
            vao.program["u_size"].value = (w, h)
            ctx.viewport = (0, rows[0], w // 4, rows[1])
            vao.render(moderngl.TRIANGLES, vertices=3)
            sampler.clear(location=0)  # leave unit 0 to the texture's own filtering
        data = fbo.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h * 3 // 2, w)

    def _setup(self, size: tuple[int, int]) -> tuple[list[tuple[Any, Any]], Any]:
        import moderngl

        ctx = self._ctx
        w, h = size
        passes = []
        for frag, filt in (
            ("i420_luma.frag", moderngl.NEAREST),
            ("i420_chroma.frag", moderngl.LINEAR),
        ):
            prog = ctx.program(
                vertex_shader=shader_source("fullscreen.vert"), fragment_shader=shader_source(frag)
            )
            prog["u_image"].value = 0
            sampler = ctx.sampler(
                texture=self._post.final_tex, filter=(filt, filt), repeat_x=False, repeat_y=False
            )
            passes.append((ctx.vertex_array(prog, []), sampler))
        target = ctx.texture((w // 4, h * 3 // 2), 4)
        return passes, ctx.framebuffer(color_attachments=[target])
