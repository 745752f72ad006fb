"""How much of a frame is lit, and how dark its background stays: figures for the show look.

A projector behind a band washes out a dim picture, so the show's lighting is judged on two
figures of a rendered frame, both on its encoded (sRGB) values with BT.709 luma weights:
:func:`lit_share`, the fraction of pixels brighter than ``LIT_LUMA`` (0.1), and, given a mask
of the pixels the drummer and the kit cover (a second render without floor and background),
:func:`background_luma`, the mean luma of every other pixel: the floor and the hall, which
must stay dark so the lit drummer stands out instead of floating in a grey fog. Pure numpy;
rendering the frames and the mask is the display services' job (``bench look``, the render
tests). Limits: luma of encoded values, not perceived lightness; one threshold.
"""

from __future__ import annotations

import numpy as np

#: The luma a pixel must exceed to count as lit.
LIT_LUMA = 0.1
_WEIGHTS = np.array([0.2126, 0.7152, 0.0722])


def luma(rgb: np.ndarray) -> np.ndarray:
    """BT.709 luma (0..1) of (H, W, 3+) uint8 pixels (their first three channels)."""
    out: np.ndarray = rgb[..., :3].astype(np.float64) @ _WEIGHTS / 255.0
    return out


def lit_share(rgb: np.ndarray, threshold: float = LIT_LUMA) -> float:
    """The fraction of pixels whose luma exceeds ``threshold``."""
    return float(np.mean(luma(rgb) > threshold))


def background_luma(rgb: np.ndarray, subject: np.ndarray) -> float:
    """Mean luma of the pixels outside ``subject`` ((H, W) bool: drummer and kit); 0 when the
    subject covers the whole frame."""
    rest = ~np.asarray(subject, bool)
    return float(luma(rgb)[rest].mean()) if rest.any() else 0.0


def hall_luma(rgb: np.ndarray, subject: np.ndarray, rows: float = 0.25) -> float:
    """Mean luma outside ``subject`` in the frame's top ``rows`` share: the hall behind the
    drummer's head, which a show keeps dark (0 when the subject covers it all)."""
    top = max(1, round(rgb.shape[0] * rows))
    return background_luma(rgb[:top], np.asarray(subject, bool)[:top])
