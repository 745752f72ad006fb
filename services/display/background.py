"""A ``--background`` value made ready to draw: the keyword or colour parsed, an image decoded.

The parsing is :func:`livedrummer.render.background.parse_background` (pure); this adds the
I/O: an image file is decoded with PyAV (already the project's video library, and FFmpeg reads
PNG, JPEG, WebP, BMP, TIFF and the first frame of a video alike) to RGB rows, top row first.
A file that is missing or does not decode is one :class:`BackgroundError` line naming it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from livedrummer.render.background import Background, BackgroundError, parse_background


def read_image(path: Path) -> np.ndarray:
    """The first picture in ``path`` as (H, W, 3) uint8, top row first."""
    import av

    if not path.is_file():
        raise BackgroundError(f"background image {path}: no such file")
    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise BackgroundError(f"background image {path}: holds no picture")
            for frame in container.decode(video=0):
                pixels: np.ndarray = frame.to_ndarray(format="rgb24")
                return np.ascontiguousarray(pixels)
    except (OSError, ValueError) as exc:  # PyAV's errors are OSError/ValueError subclasses
        raise BackgroundError(f"background image {path}: cannot decode it ({exc})") from None
    raise BackgroundError(f"background image {path}: holds no picture")


def load_background(text: str | None) -> Background:
    """The background the option ``text`` names (None: the dark hall), image decoded."""
    if text is None:
        return Background()
    bg = parse_background(text)
    if bg.kind == "image" and bg.path is not None:
        return bg.with_image(read_image(Path(bg.path)))
    return bg
