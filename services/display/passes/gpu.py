"""What every pass shares: the ``shaders/`` programs and the unit meshes, made once a renderer.

A pass asks :meth:`Gpu.vao` for a vertex array of a unit mesh and its own instance buffer;
attributes the GLSL linker dropped from a program are skipped in the buffer's layout
(:func:`used`), so one instance layout serves a program that reads all of it and a depth-only
one that reads the model matrix alone. Limits: the programs' uniforms are shared state, so
:meth:`Gpu.set_uniforms` writes a frame's camera and light values into every program that has
them, once a frame, before any pass draws.
"""

from __future__ import annotations

from typing import Any

from livedrummer.render.geometry import Mesh, all_meshes
from livedrummer.render.shaders import PROGRAMS, program_sources

#: uniforms written as raw bytes (matrices) rather than by value
_MATRICES = ("u_view_proj", "u_light_vp")


class Gpu:
    """The programs and the unit meshes' vertex and index buffers of one context."""

    def __init__(self, ctx: Any) -> None:
        self.ctx = ctx
        self.programs: dict[str, Any] = {
            name: ctx.program(vertex_shader=v, fragment_shader=f)
            for name, (v, f) in ((n, program_sources(n)) for n in PROGRAMS)
        }
        self.meshes: dict[str, Mesh] = all_meshes()
        self._vbo = {n: ctx.buffer(m.vertices.tobytes()) for n, m in self.meshes.items()}
        self._ibo = {n: ctx.buffer(m.indices.tobytes()) for n, m in self.meshes.items()}

    def vao(self, program: str, mesh: str, inst: Any, fmt: str, *names: str) -> Any:
        """A vertex array drawing unit mesh ``mesh`` once per instance of buffer ``inst``
        (layout ``fmt``, attribute ``names``) with ``program``."""
        prog = self.programs[program]
        return self.ctx.vertex_array(
            prog,
            [
                used(prog, self._vbo[mesh], "3f 3f", ("in_pos", "in_normal")),
                used(prog, inst, fmt, names),
            ],
            index_buffer=self._ibo[mesh],
        )

    def set_uniforms(self, uniforms: dict[str, Any]) -> None:
        """Write ``uniforms`` into every program that declares them."""
        for prog in self.programs.values():
            for name, value in uniforms.items():
                if name in prog:
                    if name in _MATRICES:
                        prog[name].write(value)
                    else:
                        prog[name].value = value


def used(prog: Any, buf: Any, fmt: str, names: tuple[str, ...]) -> tuple[Any, ...]:
    """A buffer binding that skips attributes the linker optimized out of ``prog``."""
    tokens = fmt.split()
    divisor = tokens[-1][tokens[-1].index("/") :] if "/" in tokens[-1] else ""
    tokens = [t.split("/")[0] for t in tokens]
    keep: list[str] = []
    out: list[str] = []
    for token, name in zip(tokens, names, strict=True):
        if name in prog:
            out.append(token)
            keep.append(name)
        else:
            count = int(token[:-1] or 1)
            out.append(f"{4 * count}x")
    return (buf, " ".join(out) + divisor, *keep)
