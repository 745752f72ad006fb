"""What is behind the stage: the dark hall, a colour, an image, chroma green, or nothing.

Stage video systems composite the drummer over their own pictures, so the frame's background
is an option (``--background``): ``#rrggbb`` (or ``#rgb``) fills it with a colour, ``chroma``
with the broadcast chroma-key green (:data:`CHROMA_GREEN`), ``transparent`` leaves it at alpha
0 (PNG frames with alpha, or a video with alpha: see :mod:`services.display.video`), and any
other value is an image file, stretched to the frame. The stage floor stays drawn in every
case and fades out at its rim, so the drummer stands on something wherever he is put.

This module is the pure part: :func:`parse_background` turns the option's text into a
:class:`Background`; decoding an image file is I/O and happens in the display services, which
put the pixels in :attr:`Background.image`. Limits: an image is stretched, not cropped to the
frame's aspect; a window cannot be transparent (its desktop shows no alpha).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from livedrummer.errors import LivedrummerError

BackgroundKind = Literal["hall", "colour", "image", "chroma", "transparent"]

#: The dark hall the stage has always stood in.
HALL = (0.02, 0.02, 0.035)
#: The usual chroma-key green (sRGB 0, 177, 64).
CHROMA_GREEN = (0.0, 177 / 255, 64 / 255)
_HEX = re.compile(r"#([0-9a-fA-F]{3}|[0-9a-fA-F]{6})")


class BackgroundError(LivedrummerError):
    """A --background value that is not a colour, a keyword or a readable image."""


@dataclass(frozen=True)
class Background:
    """The frame's background (see the module docstring)."""

    kind: BackgroundKind = "hall"
    rgb: tuple[float, float, float] = HALL
    path: str | None = None  # the image file, for kind "image"
    image: np.ndarray | None = field(default=None, compare=False, repr=False)  # (H, W, 3) u8

    @property
    def alpha(self) -> float:
        """The cleared frame's alpha: 0 for transparent, else opaque."""
        return 0.0 if self.kind == "transparent" else 1.0

    @property
    def transparent(self) -> bool:
        return self.kind == "transparent"

    def with_image(self, pixels: np.ndarray) -> Background:
        """This image background with its decoded pixels ((H, W, 3) uint8, top row first)."""
        if pixels.ndim != 3 or pixels.shape[2] != 3 or pixels.dtype != np.uint8:
            raise BackgroundError(
                f"background image {self.path}: pixels are {pixels.dtype}{pixels.shape}, "
                "want uint8 (H, W, 3)"
            )
        return replace(self, image=pixels)


def parse_colour(text: str) -> tuple[float, float, float]:
    """``#rrggbb`` or ``#rgb`` as 0..1 floats (the 8-bit values the frame will hold)."""
    if not _HEX.fullmatch(text):
        raise BackgroundError(f"background {text!r}: a colour is #rrggbb or #rgb")
    digits = text[1:]
    if len(digits) == 3:
        digits = "".join(c * 2 for c in digits)
    r, g, b = (int(digits[i : i + 2], 16) / 255 for i in (0, 2, 4))
    return (r, g, b)


def parse_background(text: str) -> Background:
    """A background from the option's text (see the module docstring)."""
    value = text.strip()
    if not value:
        raise BackgroundError("background '': give #rrggbb, chroma, transparent or an image file")
    keyword = value.lower()
    if keyword == "hall":
        return Background()
    if keyword == "chroma":
        return Background("chroma", CHROMA_GREEN)
    if keyword == "transparent":
        return Background("transparent", (0.0, 0.0, 0.0))
    if value.startswith("#"):
        return Background("colour", parse_colour(value))
    return Background("image", (0.0, 0.0, 0.0), path=value)
