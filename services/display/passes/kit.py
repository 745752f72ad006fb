"""The kit's instance buffers: one per unit mesh, all written from one instances array a frame.

:meth:`KitMesh.instances` gives every piece's model matrix, colour and material for a frame's
channels (swing, travel, glow); :meth:`KitDraw.upload` writes each unit mesh's rows into its
buffer, and the lit and the depth-only vertex arrays of that mesh read the same buffer. The
floor is drawn last and blended, so its rim fades into whatever is behind it; it receives
shadows but casts none, so it has no depth-only array. Limits: instances are rewritten whole
every frame (a few hundred rows; cheaper than tracking which moved).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.render.kitmesh import INSTANCE_FLOATS, KitMesh

from .gpu import Gpu

#: the kit instance layout: model matrix, colour, material
KIT_LAYOUT = ("16f 4f 4f/i", "in_model", "in_color", "in_material")


class KitDraw:
    """One kit's lit and depth-only instanced draws (see the module docstring)."""

    def __init__(self, gpu: Gpu, kit_mesh: KitMesh) -> None:
        self.kit_mesh = kit_mesh
        groups = kit_mesh.groups
        #: unit mesh name -> instance rows, the floor last
        self.groups = {k: groups[k] for k in sorted(groups, key=lambda k: k == "floor")}
        self._lit: list[tuple[str, Any, Any, np.ndarray]] = []
        self._depth: list[tuple[Any, np.ndarray]] = []
        for name, idx in self.groups.items():
            buf = gpu.ctx.buffer(reserve=max(1, len(idx)) * INSTANCE_FLOATS * 4, dynamic=True)
            program = "floor" if name == "floor" else "mesh"
            self._lit.append((name, gpu.vao(program, name, buf, *KIT_LAYOUT), buf, idx))
            if name != "floor":  # the floor receives shadows, it casts none
                self._depth.append((gpu.vao("depth_mesh", name, buf, *KIT_LAYOUT), idx))

    def upload(self, inst: np.ndarray) -> None:
        """Write a frame's instances (:meth:`KitMesh.instances`) into the buffers."""
        for _name, _vao, buf, idx in self._lit:
            buf.write(inst[idx].tobytes())

    def draw(self, ctx: Any) -> None:
        """Every piece lit, the floor last and blended over what is behind it."""
        self.draw_pieces()
        self.draw_floor(ctx)

    def draw_pieces(self) -> None:
        """Every piece but the floor, lit."""
        for name, vao, _buf, idx in self._lit:
            if name != "floor":
                vao.render(instances=len(idx))

    def draw_floor(self, ctx: Any, scissors: list[tuple[int, int, int, int]] | None = None) -> None:
        """The floor, lit and blended over what is behind it (its rim fades into whatever
        background is there), over the frame or once within each of ``scissors``."""
        import moderngl

        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (
            moderngl.SRC_ALPHA,
            moderngl.ONE_MINUS_SRC_ALPHA,
            moderngl.ONE,
            moderngl.ONE_MINUS_SRC_ALPHA,
        )
        for name, vao, _buf, idx in self._lit:
            if name == "floor":
                for rect in [None] if scissors is None else scissors:
                    if rect is not None:
                        ctx.scissor = rect
                    vao.render(instances=len(idx))
                if scissors is not None:
                    ctx.scissor = None
        ctx.disable(moderngl.BLEND)

    def draw_depth(self) -> None:
        """Every piece but the floor into the bound framebuffer's depth (``depth_mesh``)."""
        for vao, idx in self._depth:
            vao.render(instances=len(idx))
