"""The window's readout on small windows: twice the font's size where it fits, the font's own
size on a 640x360 window (it used to vanish under about 700 px), cropped on a thumbnail.

A real EGL context and renderer; the readout is blended into the off-screen frame exactly as a
window blends it into its own (``Readout.draw``)."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.kit.loader import load_kit
from livedrummer.render.hud import hud_image, live_lines
from services.display.surface import HeadlessSurface
from services.display.window import HUD_AT, Readout

pytestmark = pytest.mark.usefixtures("gl_ok")


@pytest.mark.parametrize(("size", "scale"), [((1280, 720), 2), ((640, 360), 1), ((160, 90), 1)])
def test_the_readout_is_shown_at_a_size_that_fits(size: tuple[int, int], scale: int) -> None:
    lines = live_lines("playing", "stage", show_help=True)
    surface = HeadlessSurface(load_kit("rock5"), size, "stage")
    try:
        surface.draw(None, 0.0)
        bare = surface.renderer.read_rgb().astype(np.int32)
        readout = Readout()
        readout.draw(surface.renderer, lines, None)
        shown = surface.renderer.read_rgb().astype(np.int32)
    finally:
        surface.close()
    whole = hud_image(lines, scale)
    h = min(whole.shape[0], size[1] - HUD_AT[1])
    w = min(whole.shape[1], size[0] - HUD_AT[0])
    assert readout.image.shape[:2] == (h, w)
    assert np.array_equal(readout.image, whole[:h, :w])  # the text at that size, cut to fit
    changed = np.any(shown != bare, axis=2)
    ys, xs = np.nonzero(changed)
    assert ys.size > 0  # the text is on the frame ...
    assert ys.min() >= HUD_AT[1] and xs.min() >= HUD_AT[0]  # ... where the readout goes
    assert ys.max() < HUD_AT[1] + h and xs.max() < HUD_AT[0] + w
