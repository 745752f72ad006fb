"""Show lighting and framing: the light rig's logic, the figure framing, and lit share on EGL."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np
import pytest

from livedrummer.body.skeleton import SegmentLengths
from livedrummer.config import Table
from livedrummer.kit.loader import load_kit
from livedrummer.render.background import parse_background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import figure_points, kit_cameras
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.lights import (
    LOOKS,
    LightError,
    look_rig,
    parse_lights,
    with_light_param,
)
from livedrummer.render.litshare import background_luma, hall_luma, lit_share
from services.display.context import DisplayError, headless_context
from services.display.renderer import Renderer

KIT = load_kit("rock5")


def test_light_directions_follow_azimuth_and_elevation() -> None:
    rig = look_rig("concert")
    up = with_light_param(rig, "wash", "elevation", 90.0).wash.direction
    assert np.allclose(up, [0.0, 0.0, 1.0])
    front = with_light_param(with_light_param(rig, "key", "elevation", 0.0), "key", "azimuth", 0)
    assert np.allclose(front.key.direction, [0.0, 1.0, 0.0])  # the audience side
    right = with_light_param(front, "key", "azimuth", 90.0).key.direction
    assert np.allclose(right, [1.0, 0.0, 0.0])


def test_a_light_parameter_changes_one_light_only() -> None:
    rig = look_rig("studio")
    out = with_light_param(rig, "rim", "intensity", 5.0)
    assert out.rim.intensity == 5.0 and out.key == rig.key and out.fill == rig.fill
    assert with_light_param(rig, "fill", "color", "#ff0000").fill.color == (1.0, 0.0, 0.0)
    assert with_light_param(rig, "fill", "g", 0.25).fill.color[1] == 0.25
    for light, param, value in (
        ("spot", "intensity", 1.0),
        ("key", "size", 1.0),
        ("key", "intensity", -1.0),
        ("key", "elevation", 120.0),
        ("key", "color", "red"),
        ("key", "r", float("nan")),
    ):
        with pytest.raises(LightError, match=light):
            with_light_param(rig, light, param, value)


def test_lights_from_toml_override_a_look_and_reject_typos() -> None:
    data = {"look": "neon", "exposure": 1.5, "key": {"intensity": 4.0, "azimuth": 10.0}}
    rig = parse_lights(Table(data, "kit.toml", "lights", LightError))
    assert rig.exposure == 1.5 and rig.key.intensity == 4.0 and rig.key.azimuth_deg == 10.0
    assert rig.fill == LOOKS["neon"].fill
    with pytest.raises(LightError, match=r"kit.toml: \[lights.key\] intensty"):
        parse_lights(Table({"key": {"intensty": 1.0}}, "kit.toml", "lights", LightError))
    with pytest.raises(LightError, match="outside"):
        parse_lights(Table({"rim": {"elevation": 100.0}}, "kit.toml", "lights", LightError))


def test_cameras_frame_the_body_of_the_avatar_at_hand() -> None:
    base = SegmentLengths()
    small = SegmentLengths(**{f.name: getattr(base, f.name) * 0.8 for f in fields(base)})
    pts_default, pts_small = figure_points(KIT), figure_points(KIT, small)
    assert pts_small[:, 2].max() < pts_default[:, 2].max() - 0.1  # a shorter head top
    near = np.linalg.norm(
        np.subtract(kit_cameras(KIT, small)["front"].eye, kit_cameras(KIT, small)["front"].target)
    )
    far = np.linalg.norm(
        np.subtract(kit_cameras(KIT)["front"].eye, kit_cameras(KIT)["front"].target)
    )
    assert near < far  # a smaller drummer is framed closer


def test_the_front_camera_sees_the_hands_over_the_toms() -> None:
    cam = kit_cameras(KIT)["front"]
    eye, snare = np.array(cam.eye), np.array(KIT.piece("snare").position_m)
    hand = snare + np.array([0.0, -0.08, 0.22])
    for name in ("tom1", "tom2"):
        tom = KIT.piece(name)
        pos = np.array(tom.position_m)
        s = (pos[1] - hand[1]) / (eye[1] - hand[1])  # where the sight line passes the tom
        line_z = hand[2] + s * (eye[2] - hand[2])
        assert line_z > pos[2] + tom.radius_m * (1.0 - abs(tom.normal[2])) - 1e-6


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


def test_default_cameras_are_lit_over_a_dark_hall(ctx: Any, rest_body: BodyScene) -> None:
    """The issue's goal on a real render: >= 35 % of the frame above luma 0.1 on front, stage
    and drummer, the hall above the drummer dark (the share is resolution-independent to
    about a point, so a small frame keeps the test fast)."""
    size = (256, 144)
    frame = next(iter(rest_body.frames(np.array([6.5]))))
    lit_r = Renderer(ctx, build_kit_mesh(KIT), BODY_SKELETON, size, samples=0)
    bare = Renderer(
        ctx,
        build_kit_mesh(KIT, floor=False),
        BODY_SKELETON,
        size,
        samples=0,
        background=parse_background("transparent"),
    )
    dark = Renderer(
        ctx,
        build_kit_mesh(KIT),
        BODY_SKELETON,
        size,
        samples=0,
        lights=with_light_param(look_rig("concert"), "key", "intensity", 0.0),
    )
    for name in ("front", "stage", "drummer"):
        cam = kit_cameras(KIT)[name]
        lit_r.draw(frame, cam)
        rgb = lit_r.read_rgb()
        bare.draw(frame, cam)
        mask = bare.read_rgba_top()[..., 3] > 0
        assert lit_share(rgb) >= 0.35, name
        assert background_luma(rgb, mask) < 0.15, name
        if name != "drummer":
            assert hall_luma(rgb, mask) < 0.05, name
        dark.draw(frame, cam)
        assert lit_share(dark.read_rgb()) < lit_share(rgb) - 0.02, name  # the key lights it


@pytest.fixture(scope="module")
def rest_body() -> BodyScene:
    from livedrummer.body.perform import perform
    from livedrummer.body.rig import build_rig
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from services.cli.files import DEMO_MAP, demo_groove

    note_map = load_note_map(DEMO_MAP)
    return BodyScene(
        KIT, perform(read_midi_file(demo_groove(), note_map), build_rig(KIT), note_map)
    )
