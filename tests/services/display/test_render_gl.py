"""Headless OpenGL (EGL, llvmpipe without a GPU): shaders compile, pixels land where they should.

Skipped only where no EGL context can be made at all (see deploy/system-deps.sh).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scene_rest import REST_SKELETON, rest_frame

from livedrummer.kit.loader import load_kit
from livedrummer.render.camera import Camera, kit_cameras
from livedrummer.render.kitmesh import STAGE_RADIUS_M, basis, build_kit_mesh, empty_stage
from livedrummer.render.scene import CH_HIGHLIGHT, SceneFrame, empty_channels
from services.display.context import DisplayError, headless_context
from services.display.renderer import BACKGROUND, Renderer

W, H = 320, 180
KIT = load_kit("rock5")
BG = np.round(np.array(BACKGROUND) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


def project(cam: Camera, points: np.ndarray) -> np.ndarray:
    """World points (N, 3) to pixel (x right, y down) coordinates (N, 2)."""
    clip = np.c_[points, np.ones(len(points))] @ cam.view_projection(W / H).T.astype(np.float64)
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * W, (1 - ndc[:, 1]) / 2 * H]


def inside(poly: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Even-odd point-in-polygon for pixel centre grids."""
    result = np.zeros(x.shape, bool)
    px, py = poly[:, 0], poly[:, 1]
    for i in range(len(poly)):
        x0, y0, x1, y1 = px[i - 1], py[i - 1], px[i], py[i]
        crosses = (y0 > y) != (y1 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        result ^= crosses & (x < xi)
    return result


def ring(centre: np.ndarray, normal: np.ndarray, radius: float, n: int = 64) -> np.ndarray:
    rot = basis(normal)
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return centre + radius * (np.cos(a)[:, None] * rot[:, 0] + np.sin(a)[:, None] * rot[:, 1])


def no_body(sticks: np.ndarray | None = None, channels: np.ndarray | None = None) -> SceneFrame:
    away = np.zeros((2, 2, 3), np.float32)
    away[..., 2] = -1.0  # below the stage floor: hidden
    return SceneFrame(
        np.zeros((0, 3), np.float32),
        away if sticks is None else sticks.astype(np.float32),
        empty_channels(len(KIT.pieces)) if channels is None else channels,
    )


@pytest.mark.parametrize("camera", ["stage", "front", "left"])
def test_nothing_is_drawn_beyond_the_stage(ctx: Any, camera: str) -> None:
    cam = kit_cameras(KIT)[camera]
    r = Renderer(ctx, empty_stage(), None, (W, H))
    r.draw(None, cam)
    img = r.read_rgb()
    edge = project(cam, ring(np.zeros(3), np.array([0.0, 0, 1]), STAGE_RADIUS_M, 256))
    ys, xs = np.mgrid[0:H, 0:W] + 0.5
    floor = inside(edge, xs, ys)
    near = np.zeros_like(floor)
    for dy in range(-2, 3):  # stay 2 px clear of the (antialiased) edge
        for dx in range(-2, 3):
            near |= np.roll(np.roll(floor, dy, 0), dx, 1)
    outside = ~near
    assert outside.sum() > 0.1 * W * H
    assert np.all(img[outside] == BG)
    assert np.any(img[floor] != BG)


def test_the_struck_piece_lights_up(ctx: Any) -> None:
    cam = kit_cameras(KIT)["overhead"]
    r = Renderer(ctx, build_kit_mesh(KIT), None, (W, H))
    r.draw(no_body(), cam)
    before = r.read_rgb().astype(int)
    snare = KIT.pieces.index(KIT.piece("snare"))
    ch = empty_channels(len(KIT.pieces))
    ch[snare, CH_HIGHLIGHT] = 1.0
    r.draw(no_body(channels=ch), cam)
    after = r.read_rgb().astype(int)
    piece = KIT.piece("snare")
    c = np.array(piece.position_m)
    x, y = project(cam, c[None])[0].astype(int)
    assert after[y, x].sum() - before[y, x].sum() > 150
    changed = np.abs(after - before).sum(axis=2) > 6
    outline = project(
        cam,
        np.r_[
            ring(c, piece.normal, piece.radius_m * 1.05),
            ring(c - piece.depth_m * piece.normal, piece.normal, piece.radius_m * 1.05),
        ],
    )
    ys, xs = np.nonzero(changed)
    assert xs.min() >= outline[:, 0].min() - 2 and xs.max() <= outline[:, 0].max() + 2
    assert ys.min() >= outline[:, 1].min() - 2 and ys.max() <= outline[:, 1].max() + 2


def test_stick_tip_is_drawn_over_the_struck_piece(ctx: Any) -> None:
    cam = kit_cameras(KIT)["overhead"]
    piece = KIT.piece("snare")
    tip = np.array(piece.position_m) + 0.012 * piece.normal + np.array([0.04, -0.03, 0.0])
    back = np.array([0.3, -0.35, 0.3]) / np.linalg.norm([0.3, -0.35, 0.3])
    sticks = np.array([[tip + 0.41 * back, tip], [[0, 0, -1.0], [0.1, 0, -1.0]]])
    ch = empty_channels(len(KIT.pieces))
    ch[KIT.pieces.index(piece), CH_HIGHLIGHT] = 1.0
    # no shadows: the hi-hat's shadow falls on the snare head where the stick is looked for
    r = Renderer(ctx, build_kit_mesh(KIT), None, (W, H), shadows=False)
    r.draw(no_body(channels=ch), cam)
    without = r.read_rgb().astype(int)
    r.draw(no_body(sticks, ch), cam)
    with_stick = r.read_rgb().astype(int)
    head = project(cam, ring(np.array(piece.position_m), piece.normal, piece.radius_m))
    tx, ty = project(cam, tip[None])[0]
    assert inside(head, np.array([tx]), np.array([ty]))[0]
    x, y = project(cam, (tip + 0.025 * back)[None])[0].astype(int)
    px = with_stick[y, x]
    assert np.abs(px - without[y, x]).sum() > 60
    assert px[0] > px[2] + 40  # warm wood, not the white highlighted head


def test_the_drummer_is_drawn_from_the_pose(ctx: Any) -> None:
    cam = kit_cameras(KIT)["front"]
    r = Renderer(ctx, build_kit_mesh(KIT), REST_SKELETON, (W, H))
    frame = rest_frame(KIT)
    r.draw(frame, cam)
    img = r.read_rgb().astype(int)
    r.draw(no_body(), cam)
    empty = r.read_rgb().astype(int)
    head = frame.joints_m[REST_SKELETON.index("head")]
    x, y = project(cam, head[None])[0].astype(int)
    assert np.abs(img[y, x] - empty[y, x]).sum() > 100
    assert img[y, x, 0] > img[y, x, 1] > img[y, x, 2]  # lit skin
    # Moving the pose moves the drawing: the head raised 20 cm is drawn higher.
    raised = frame.joints_m.copy()
    raised[:, 2] += 0.2
    r.draw(SceneFrame(raised, frame.sticks_m, frame.channels), cam)
    up = r.read_rgb().astype(int)
    x2, y2 = project(cam, raised[[REST_SKELETON.index("head")]])[0].astype(int)
    assert y2 < y and up[y2, x2, 0] > up[y2, x2, 2]


def test_multisampled_and_plain_frames_agree_away_from_edges(ctx: Any) -> None:
    cam = kit_cameras(KIT)["stage"]
    frame = rest_frame(KIT)
    plain = Renderer(ctx, build_kit_mesh(KIT), REST_SKELETON, (W, H), samples=0)
    msaa = Renderer(ctx, build_kit_mesh(KIT), REST_SKELETON, (W, H), samples=4)
    plain.draw(frame, cam)
    msaa.draw(frame, cam)
    a, b = plain.read_rgb().astype(int), msaa.read_rgb().astype(int)
    assert np.median(np.abs(a - b).sum(axis=2)) <= 3
