"""Pure rendering data: meshes, kit instances, cameras, the body as a scene, transport; no GL.

Everything here is numpy and frozen dataclasses so it can be tested without a GPU; the OpenGL
side (context, buffers, programs, window, video files) lives in :mod:`services.display` and only
copies these arrays into buffers.
"""
