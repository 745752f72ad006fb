"""Pure rendering data: meshes, kit instances, cameras, kit animation, transport; no OpenGL.

Everything here is numpy and frozen dataclasses so it can be tested without a GPU; the OpenGL
side (context, buffers, programs, window, video files) lives in :mod:`services.display` and only
copies these arrays into buffers.
"""
