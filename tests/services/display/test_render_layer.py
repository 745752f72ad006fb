"""The static layer (``services/display/passes/layer.py``) on a real EGL context: a frame drawn
from the cached kit at rest plus what differs from it equals the fully drawn frame, pixel for
pixel, as pieces swing, heads glow and the drummer plays, from every camera; and the pure
tile geometry (``livedrummer/render/shadow_region.py``) covers what it must.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from livedrummer.render.shadow_region import box_corners, box_rects, tile_cover

GROOVE = Path(__file__).resolve().parents[3] / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


@pytest.mark.usefixtures("gl_ok")
@pytest.mark.parametrize("config", ["fxaa", "no_shadows", "image", "mannequin"])
def test_a_frame_from_the_layer_equals_the_fully_drawn_frame(config: str) -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from livedrummer.render.background import Background
    from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
    from livedrummer.render.camera import CAMERA_NAMES, pick_camera
    from livedrummer.render.kitmesh import build_kit_mesh
    from livedrummer.render.scene import CH_HIGHLIGHT, CH_TRAVEL, CH_WOBBLE
    from services.cli.files import DEMO_MAP
    from services.display.context import headless_context
    from services.display.renderer import Renderer

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(GROOVE, note_map), kit, note_map)
    frames = list(body.frames(np.array([3.0, 4.05, 6.1, 8.2])))
    moving = [np.abs(f.channels[:, [CH_WOBBLE, CH_TRAVEL]]).max() for f in frames]
    assert max(moving) > 0.01  # pieces swing or travel
    assert max(f.channels[:, CH_HIGHLIGHT].max() for f in frames) > 0.05  # heads glow
    image = (np.arange(36 * 64 * 3) % 251).astype(np.uint8).reshape(36, 64, 3)
    kw: dict[str, Any] = {
        "fxaa": {"fxaa": True},
        "no_shadows": {"shadows": False},
        "image": {"background": Background(kind="image", image=image)},
        "mannequin": {"avatar": "mannequin"},
    }[config]
    ctx = headless_context()
    try:
        size = (256, 144)
        layered = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, **kw)
        full = Renderer(
            ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, static_layer=False, **kw
        )
        assert layered.layer is not None and full.layer is None
        redrawn = []
        for name in CAMERA_NAMES:
            cam = pick_camera(kit, name)
            for frame in [*frames, None]:
                layered.draw(frame, cam)
                a = layered.read_rgba_top()
                full.draw(frame, cam)
                b = full.read_rgba_top()
                assert np.array_equal(a, b), (name, None if frame is None else frame.time_s)
                rects = layered.layer.last_rects
                redrawn.append(sum(r[2] * r[3] for r in rects) / (size[0] * size[1]))
        assert min(redrawn) == 0.0  # the kit at rest, no drummer: the layer alone
        assert float(np.median(redrawn)) < 0.8  # the layer was used, not whole-frame redraws
        # a camera moving every frame: the full path (the layer is not rebuilt), same pixels
        from livedrummer.render.camera import Camera

        held = layered.layer._key
        for k, frame in enumerate(frames):
            cam = Camera("move", (0.5 * k, -3.0, 1.6), (0.0, 0.3, 0.7))
            layered.draw(frame, cam)
            full.draw(frame, cam)
            assert np.array_equal(layered.read_rgba_top(), full.read_rgba_top())
        assert layered.layer._key == held
    finally:
        ctx.release()


def test_the_tiles_cover_every_box_and_do_not_overlap() -> None:
    rng = np.random.default_rng(3)
    size = (320, 180)
    lo = rng.integers(0, 300, (12, 2))
    boxes = np.c_[lo, lo + rng.integers(1, 60, (12, 2))].clip(0, [320, 180, 320, 180])
    tiles = tile_cover(boxes, size, tile=16)
    cover = np.zeros(size[::-1], np.int64)
    for x, y, w, h in tiles:
        cover[y : y + h, x : x + w] += 1
    assert cover.max() == 1  # no pixel drawn twice
    for x0, y0, x1, y1 in boxes:
        assert (cover[y0:y1, x0:x1] == 1).all()
    assert tile_cover(np.zeros((0, 4), np.int64), size) == []


def test_a_box_projects_inside_its_pixel_box() -> None:
    from livedrummer.render.camera import Camera

    size = (320, 180)
    vp = Camera("t", (0.0, -4.0, 2.0), (0.0, 0.0, 0.5)).view_projection(size[0] / size[1])
    lo, hi = np.array([[-0.3, -0.2, 0.1]]), np.array([[0.4, 0.3, 0.9]])
    ((x0, y0, x1, y1),) = box_rects(box_corners(lo, hi), vp, size)
    rng = np.random.default_rng(5)
    p = lo + rng.random((500, 3)) * (hi - lo)
    clip = np.c_[p, np.ones(len(p))] @ vp.T.astype(np.float64)
    px = (clip[:, :2] / clip[:, 3:4] * 0.5 + 0.5) * np.array(size)
    assert (px[:, 0] >= x0).all() and (px[:, 0] <= x1).all()
    assert (px[:, 1] >= y0).all() and (px[:, 1] <= y1).all()
    behind = np.array([[[0.0, -5.0, 2.0], [0.0, 0.0, 0.5]]])  # a point behind the eye
    assert box_rects(behind, vp, size).tolist() == [[0, 0, *size]]


@pytest.mark.usefixtures("gl_ok")
@pytest.mark.parametrize("fxaa", [True, False])
def test_a_window_frame_drawn_through_the_layer_and_presented_equals_the_full_path(
    fxaa: bool,
) -> None:
    """The live window's renderer (``WindowSurface``: off screen, the layer) presented into
    a screen-like framebuffer (colour and depth renderbuffers) by one blit: the same pixels as
    the full path presented the same way, and as its own read-back, overlays included."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
    from livedrummer.render.camera import pick_camera
    from livedrummer.render.kitmesh import build_kit_mesh
    from services.cli.files import DEMO_MAP
    from services.display.context import headless_context
    from services.display.renderer import Renderer

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(GROOVE, note_map), kit, note_map)
    frames = list(body.frames(np.array([3.0, 4.05, 6.1])))
    hud = np.zeros((20, 60, 4), np.uint8)
    hud[..., 0], hud[..., 3] = 250, 160
    ctx = headless_context()
    try:
        size = (256, 144)
        screen = ctx.framebuffer(
            color_attachments=[ctx.renderbuffer(size, 4)],
            depth_attachment=ctx.depth_renderbuffer(size),
        )
        kw: dict[str, Any] = {"samples": 0, "fxaa": fxaa}
        layered = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, **kw)
        full = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, static_layer=False, **kw)
        assert layered.layer is not None and full.layer is None
        cam = pick_camera(kit, "stage")
        calls = []
        layer_draw = layered.layer.draw

        def counted(*args: Any) -> None:
            calls.append(1)
            layer_draw(*args)

        layered.layer.draw = counted  # type: ignore[method-assign, assignment]
        shown, used = [], []
        # the same frame twice, overlays between: with FXAA the second is not drawn again
        for frame in [*frames, frames[-1], None, None]:
            for r in (layered, full):
                screen.clear(0.0, 0.0, 1.0, 1.0)
                r.draw(frame, cam)
                r.draw_overlay(hud, (8, 8, 60, 20))
                r.present(screen)
                got = np.frombuffer(screen.read(components=4), np.uint8).reshape(144, 256, 4)
                assert np.array_equal(got, r.read_rgba())  # one copy, nothing lost
                shown.append(got.copy())
            assert np.array_equal(shown[-2], shown[-1]), None if frame is None else frame.time_s
            area = sum(r[2] * r[3] for r in layered.layer.last_rects) / (size[0] * size[1])
            used.append(layered.layer._key is not None and frame is not None and area < 0.8)
        assert any(used)  # the frames came from the layer, a part redrawn: not the full path
        layered_frames = 6 - 1  # the first frame builds nothing: the view has not held yet
        assert len(calls) == (layered_frames - 2 if fxaa else layered_frames)
        assert (shown[0][144 - 28 : 144 - 8, 8:68, 0] > 150).all()  # the HUD is in the copy
        with pytest.raises(ValueError, match="window"):
            Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, offscreen=False).present(screen)
    finally:
        ctx.release()
