"""Cached drawing is exact: a frame drawn from the cached static shadow map equals one whose
every caster was drawn again (headless EGL), while the kit's pieces swing and the drummer plays.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

GROOVE = Path(__file__).resolve().parents[3] / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


@pytest.mark.usefixtures("gl_ok")
def test_the_cached_static_shadow_map_gives_the_fully_redrawn_frame() -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
    from livedrummer.render.camera import pick_camera
    from livedrummer.render.kitmesh import build_kit_mesh
    from livedrummer.render.scene import CH_TRAVEL, CH_WOBBLE
    from services.cli.files import DEMO_MAP
    from services.display.context import headless_context
    from services.display.renderer import Renderer

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(GROOVE, note_map), kit, note_map)
    frames = list(body.frames(np.array([2.0, 4.05, 6.1, 8.2])))
    moving = [np.abs(f.channels[:, [CH_WOBBLE, CH_TRAVEL]]).max() for f in frames]
    assert max(moving) > 0.01  # pieces swing or travel in these frames: the cache is tried
    ctx = headless_context()
    try:
        cam = pick_camera(kit, "stage")
        size = (320, 180)
        cached = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, fxaa=True)
        full = Renderer(
            ctx,
            build_kit_mesh(kit),
            BODY_SKELETON,
            size,
            samples=0,
            fxaa=True,
            cache_static_shadow=False,
        )
        assert cached.cache_static_shadow and not full.cache_static_shadow
        for frame in frames:
            cached.draw(frame, cam)
            a = cached.read_rgb().astype(int)
            map_a = np.frombuffer(cached._shadow_map.read(), np.float32)
            full.draw(frame, cam)
            b = full.read_rgb().astype(int)
            map_b = np.frombuffer(full._shadow_map.read(), np.float32)
            assert np.array_equal(map_a, map_b)  # the same depths, texel for texel
            assert map_a.min() < 0.99  # something was drawn into it
            assert np.abs(a - b).max() <= 1
    finally:
        ctx.release()
