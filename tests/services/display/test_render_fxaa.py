"""The FXAA pass (``render``'s default anti-aliasing) in a real EGL context: edges move towards
the 4x multisampled picture, flat regions stay as drawn, and ``--aa`` reads fxaa or a count."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from livedrummer.errors import LivedrummerError
from livedrummer.kit.loader import load_kit
from livedrummer.render.background import parse_background
from livedrummer.render.body_scene import BODY_SKELETON
from livedrummer.render.camera import kit_cameras
from livedrummer.render.kitmesh import build_kit_mesh
from services.cli.picture import parse_aa
from services.display.context import DisplayError, headless_context
from services.display.renderer import Renderer

KIT = load_kit("rock5")
SIZE = (320, 180)


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


def frame(ctx: Any, **kw: Any) -> np.ndarray:
    r = Renderer(ctx, build_kit_mesh(KIT), BODY_SKELETON, SIZE, **kw)
    r.draw(None, kit_cameras(KIT)["front"])
    first = r.read_rgba_top().astype(np.float64)
    # bit-exact by design: one frame read twice from the same framebuffer
    assert np.array_equal(r.read_rgba_top(), first)  # the pass runs once per frame
    return first


def test_fxaa_brings_edges_towards_multisampling(ctx: Any) -> None:
    plain, fxaa, msaa = frame(ctx, samples=0), frame(ctx, samples=0, fxaa=True), frame(ctx)
    edge = np.abs(plain - msaa)[..., :3].sum(-1) > 30
    assert edge.sum() > 200
    before = np.abs(plain - msaa)[edge][:, :3].mean()
    after = np.abs(fxaa - msaa)[edge][:, :3].mean()
    assert after < 0.75 * before
    changed = np.abs(fxaa - plain)[..., :3].sum(-1) > 0
    assert changed.sum() < 0.3 * changed.size  # only edges are touched
    assert np.abs(fxaa - plain)[~edge][:, :3].mean() < 1.0


def test_fxaa_keeps_a_transparent_background_clear(ctx: Any) -> None:
    bg = parse_background("transparent")
    plain = frame(ctx, samples=0, background=bg)
    fxaa = frame(ctx, samples=0, fxaa=True, background=bg)
    clear = plain[..., 3] == 0
    assert clear.sum() > 0.1 * clear.size
    # the silhouette's alpha is smoothed a pixel deep; away from it nothing appears
    padded = np.pad(clear, 2, constant_values=True)
    inner = clear.copy()
    for dy in range(5):  # clear in the whole 5x5 box round the pixel
        for dx in range(5):
            inner &= padded[dy : dy + clear.shape[0], dx : dx + clear.shape[1]]
    assert np.all(fxaa[inner, 3] == 0)


def test_aa_option_reads_fxaa_or_a_count() -> None:
    assert parse_aa("fxaa") == (0, True)
    assert parse_aa("4") == (4, False) and parse_aa("0") == (0, False)
    for bad in ("3", "x"):
        with pytest.raises(LivedrummerError, match=f"--aa {bad}: expected"):
            parse_aa(bad)
