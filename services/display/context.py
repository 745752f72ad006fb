"""Headless OpenGL contexts: EGL first (Mesa llvmpipe where there is no GPU).

``moderngl`` can create a stand-alone context through EGL without any display server, which
is what a render farm, CI or a stage laptop over SSH has. When EGL cannot load (no libEGL,
no Mesa), the error names the Debian packages that provide it (see ``deploy/system-deps.sh``).

Mesa's software rasterizer (llvmpipe) shades with ``LP_NUM_THREADS`` threads, read when the
driver loads; left unset it counts the machine's processors, not those the process may run on
(a container's or a ``taskset`` share). :func:`use_cpu_cores` sets it to the cores the process
is allowed, unless the caller (a worker process splitting the cores, the user) set it already.
"""

from __future__ import annotations

import logging
import os
from typing import Any

from livedrummer.errors import LivedrummerError

log = logging.getLogger(__name__)

GL_VERSION = 330


class DisplayError(LivedrummerError):
    """No OpenGL context could be made, or a window or video file could not be opened."""


def use_cpu_cores() -> int:
    """Let llvmpipe use every core this process may run on (``LP_NUM_THREADS``, unless set
    already); the thread count it will use. Call before the first context of the process."""
    if "LP_NUM_THREADS" not in os.environ:
        os.environ["LP_NUM_THREADS"] = str(len(os.sched_getaffinity(0)))
    try:
        return int(os.environ["LP_NUM_THREADS"])
    except ValueError:
        return 0  # Mesa's own reading of a malformed value


def headless_context() -> Any:
    """A stand-alone OpenGL 3.3 core context over EGL."""
    import moderngl

    use_cpu_cores()
    try:
        create: Any = moderngl.create_context  # its stub types ``backend`` wrongly
        ctx = create(standalone=True, backend="egl", require=GL_VERSION)
    except Exception as exc:  # moderngl/glcontext raise bare Exception subclasses
        raise DisplayError(
            f"no headless OpenGL context (EGL): {exc}; install libegl1 libegl-mesa0 "
            "libgl1-mesa-dri (deploy/system-deps.sh)"
        ) from None
    log.info("OpenGL: %s, %s", ctx.info.get("GL_RENDERER"), ctx.info.get("GL_VERSION"))
    return ctx
