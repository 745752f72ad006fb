"""A second drummer drawn translucent over the first: the ghost's colours from its own render.

The teacher's ghost is rendered alone (no kit, no floor) on a transparent background, so its
alpha is the body's coverage. :func:`ghost_image` turns that render into an overlay image the
renderer blends over the player's frame: the body's shading kept as brightness, recoloured with
one tint (:data:`GHOST_TINT`, a cyan no part of the built-in character or kit wears, so a test
or a viewer tells the ghost's pixels from everything else) at a fixed opacity. Pure numpy on
``(H, W, 4)`` uint8 arrays, straight alpha, top row first (the overlay's format).

Limits: the ghost is blended over the player, not depth-tested against it (it is seen through
the player's arms, which is the point of a ghost); its shading is the render's, not re-lit.
"""

from __future__ import annotations

import numpy as np

#: The ghost's colour (RGB 0..255) and opacity (0..1).
GHOST_TINT = (40, 235, 255)
GHOST_ALPHA = 0.4


def ghost_image(
    rgba: np.ndarray, tint: tuple[int, int, int] = GHOST_TINT, alpha: float = GHOST_ALPHA
) -> np.ndarray:
    """The overlay of a body render ``rgba`` (see the module docstring)."""
    if rgba.ndim != 3 or rgba.shape[2] != 4 or rgba.dtype != np.uint8:
        raise ValueError(f"expected (H, W, 4) uint8, got {rgba.shape} {rgba.dtype}")
    out = np.zeros_like(rgba)
    on = rgba[..., 3] > 0  # the body covers a tenth of the frame: only its pixels are worked
    body = rgba[on]
    brightest = body[:, :3].max(axis=1).astype(np.float32) * (1.6 / 255.0)
    light = 0.45 + 0.55 * np.minimum(brightest, 1.0)
    out[on, :3] = np.clip(light[:, None] * np.asarray(tint, np.float32), 0, 255).astype(np.uint8)
    out[on, 3] = (body[:, 3].astype(np.float32) * alpha).astype(np.uint8)
    return out


def tint_fraction(rgb: np.ndarray, tint: tuple[int, int, int] = GHOST_TINT) -> float:
    """The fraction of ``rgb``'s pixels ((H, W, 3) uint8) with the tint's hue: blue and green
    well above red, as no other part of the scene is (for tests and checks)."""
    x = rgb.astype(np.int32)
    r, g, b = x[..., 0], x[..., 1], x[..., 2]
    hit = (
        (g > r + 40) & (b > r + 40) & (abs(g - b) < 90)
        if tint == GHOST_TINT
        else (np.all(np.abs(x - np.asarray(tint)) < 40, axis=2))
    )
    return float(np.count_nonzero(hit)) / max(1, hit.size)
