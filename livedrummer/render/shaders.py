"""Shader sources from ``shaders/``, with ``#include "file"`` resolved; no OpenGL needed.

Shaders are package data (:func:`livedrummer.resources.data_dir`), read once and cached. GLSL
has no include, so a line ``#include "name.glsl"`` is replaced by that file's text (once per
program, nested includes allowed, cycles rejected); everything else reaches the driver as
written, so a driver's line numbers point into the expanded text. :data:`PROGRAMS` names the
vertex/fragment pairs the renderer links.
"""

from __future__ import annotations

import functools
import re

from livedrummer.errors import LivedrummerError
from livedrummer.resources import data_dir

_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)

#: program name -> (vertex shader file, fragment shader file)
PROGRAMS: dict[str, tuple[str, str]] = {
    "mesh": ("mesh.vert", "lit.frag"),
    "floor": ("mesh.vert", "floor.frag"),
    "segment": ("segment.vert", "lit.frag"),
    "ball": ("ball.vert", "lit.frag"),
    "skin": ("skin.vert", "skin.frag"),
    # depth-only twins of the casters, for the key light's shadow map
    "depth_mesh": ("mesh.vert", "depth.frag"),
    "depth_segment": ("segment.vert", "depth.frag"),
    "depth_ball": ("ball.vert", "depth.frag"),
    "depth_skin": ("skin.vert", "depth.frag"),
}


class ShaderError(LivedrummerError):
    """A shader file is missing, or its includes are broken."""


@functools.cache
def shader_source(name: str) -> str:
    """The text of ``shaders/name`` with includes expanded."""
    return _expand(name, ())


def _expand(name: str, stack: tuple[str, ...]) -> str:
    if name in stack:
        raise ShaderError(f"shader include cycle: {' -> '.join((*stack, name))}")
    path = data_dir("shaders") / name
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        where = f" (included from {stack[-1]})" if stack else ""
        raise ShaderError(f"cannot read shader {path}{where}: {exc.strerror}") from None
    return _INCLUDE.sub(lambda m: _expand(m.group(1), (*stack, name)), text)


def program_sources(program: str) -> tuple[str, str]:
    """Vertex and fragment source of a program named in :data:`PROGRAMS`."""
    vert, frag = PROGRAMS[program]
    return shader_source(vert), shader_source(frag)
