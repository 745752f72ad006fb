"""Pure scene data: skeleton contract, rest pose, kit instances, geometry, shaders, cameras."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scene_rest import REST_SKELETON, rest_frame

from livedrummer.kit.loader import load_kit
from livedrummer.render.camera import (
    CAMERA_NAMES,
    CameraError,
    CameraMove,
    kit_cameras,
    pick_camera,
)
from livedrummer.render.geometry import all_meshes
from livedrummer.render.kitmesh import MOTION_BEATER, MOTION_LIFT, build_kit_mesh
from livedrummer.render.scene import (
    CH_HIGHLIGHT,
    CH_TRAVEL,
    CH_WOBBLE,
    CH_WOBBLE_AZIMUTH,
    SceneError,
    SceneFrame,
    Skeleton,
    Tone,
    empty_channels,
)
from livedrummer.render.shaders import PROGRAMS, ShaderError, shader_source


@pytest.fixture(scope="module")
def kit():  # type: ignore[no-untyped-def]
    return load_kit("rock5")


def test_skeleton_rejects_a_parent_after_its_child() -> None:
    with pytest.raises(SceneError, match="parent"):
        Skeleton(
            ("a", "b"),
            np.array([1, -1], np.int32),
            np.ones(2, np.float32),
            np.ones(2, np.float32),
            np.zeros(2, np.uint8),
        )
    with pytest.raises(SceneError, match="not a joint"):
        Skeleton.build([("a", None, 0.1, 0.1, Tone.SKIN), ("b", "zz", 0.1, 0.1, Tone.SKIN)])


def test_frame_check_names_the_bad_field(kit) -> None:  # type: ignore[no-untyped-def]
    good = rest_frame(kit)
    good.check(REST_SKELETON, len(kit.pieces))
    bad = SceneFrame(good.joints_m.astype(np.float64), good.sticks_m, good.channels)
    with pytest.raises(SceneError, match="joints_m"):
        bad.check(REST_SKELETON, len(kit.pieces))
    with pytest.raises(SceneError, match="channels"):
        good.check(REST_SKELETON, len(kit.pieces) + 1)


def test_rest_pose_sits_on_the_throne_with_sticks_on_hihat_and_snare(kit) -> None:  # type: ignore[no-untyped-def]
    f = rest_frame(kit)
    pelvis = f.joints_m[REST_SKELETON.index("pelvis")]
    assert kit.seat_height_m < pelvis[2] < kit.seat_height_m + 0.2
    hihat, snare = np.array(kit.piece("hihat").position_m), np.array(kit.piece("snare").position_m)
    assert np.linalg.norm(f.sticks_m[0, 1] - hihat) < 0.05  # right stick tip
    assert np.linalg.norm(f.sticks_m[1, 1] - snare) < 0.05  # left stick tip
    # Bones keep plausible lengths (no limb stretched across the kit).
    bones = REST_SKELETON.bones
    lengths = np.linalg.norm(f.joints_m[bones] - f.joints_m[REST_SKELETON.parent[bones]], axis=1)
    assert lengths.max() < 0.5


def test_rest_pose_follows_a_mirrored_kit(kit) -> None:  # type: ignore[no-untyped-def]
    left = kit.mirrored()
    f = rest_frame(left)
    hihat = np.array(left.piece("hihat").position_m)
    assert hihat[0] > 0
    assert np.linalg.norm(f.sticks_m[1, 1] - hihat) < 0.05  # now the left hand's stick


def test_lathe_normals_are_unit_and_outward() -> None:
    meshes = all_meshes()
    for mesh in meshes.values():
        n = mesh.vertices[:, 3:]
        assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-5), mesh.name
        assert mesh.indices.max() < len(mesh.vertices)
    disc = meshes["disc"].vertices
    assert np.allclose(disc[:, 5], 1.0)
    cyl = meshes["cylinder"].vertices
    assert np.allclose(np.sum(cyl[:, :2] * cyl[:, 3:5], axis=1), 1.0, atol=1e-5)


def _centre(inst: np.ndarray) -> np.ndarray:
    return inst[:, 12:15]  # translation column of the column-major matrix


def test_kit_instances_follow_the_channels(kit) -> None:  # type: ignore[no-untyped-def]
    mesh = build_kit_mesh(kit)
    assert set(range(len(kit.pieces))) <= set(mesh.piece.tolist())
    rest = mesh.instances(empty_channels(len(kit.pieces)))
    assert np.all(rest[:, 19] == 0)

    crash = kit.pieces.index(kit.piece("crash1"))
    ch = empty_channels(len(kit.pieces))
    ch[crash, CH_HIGHLIGHT] = 1.0
    ch[crash, CH_WOBBLE] = 0.3
    ch[crash, CH_WOBBLE_AZIMUTH] = 0.0  # tilt about +x
    moved = mesh.instances(ch)
    own = mesh.piece == crash
    assert moved[own, 19].max() == pytest.approx(1.0)
    assert np.all(moved[~own, 19] == 0)
    assert np.array_equal(moved[~own], rest[~own])
    cym = np.flatnonzero(own & (mesh.mesh == "cymbal"))[0]
    z_rest, z_moved = rest[cym, 8:11], moved[cym, 8:11]  # the instance's z axis
    c, s = math.cos(0.3), math.sin(0.3)
    about_x = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    assert np.allclose(z_moved, about_x @ z_rest, atol=1e-6)
    pivot = np.array(kit.piece("crash1").position_m)
    centre_moved = about_x @ (_centre(rest[[cym]])[0] - pivot) + pivot
    assert np.allclose(_centre(moved[[cym]])[0], centre_moved, atol=1e-6)

    hat = kit.pieces.index(kit.piece("hihat"))
    ch = empty_channels(len(kit.pieces))
    ch[hat, CH_TRAVEL] = 0.02
    lifted = mesh.instances(ch)
    top = mesh.motion == MOTION_LIFT
    shift = _centre(lifted[top]) - _centre(rest[top])
    assert np.allclose(shift, 0.02 * kit.piece("hihat").normal, atol=1e-6)

    kick = kit.pieces.index(kit.piece("kick"))
    ch = empty_channels(len(kit.pieces))
    ch[kick, CH_TRAVEL] = 0.5
    swung = mesh.instances(ch)
    ball = np.flatnonzero((mesh.motion == MOTION_BEATER) & (mesh.mesh == "sphere"))[0]
    away = _centre(swung[[ball]])[0] - _centre(rest[[ball]])[0]
    assert np.dot(away, kit.piece("kick").normal) > 0.02  # back towards the drummer


def test_mirrored_kit_instances_mirror(kit) -> None:  # type: ignore[no-untyped-def]
    a = build_kit_mesh(kit, floor=False)
    b = build_kit_mesh(kit.mirrored(), floor=False)
    assert len(a.mesh) == len(b.mesh)
    ca, cb = a.model[:, :3, 3], b.model[:, :3, 3]
    assert np.allclose(ca[:, 0], -cb[:, 0], atol=1e-9)


def test_shaders_expand_includes_and_declare_a_version() -> None:
    for vert, frag in PROGRAMS.values():
        for name in (vert, frag):
            src = shader_source(name)
            assert src.startswith("#version 330"), name
            assert "#include" not in src
    assert "vec3 shade(" in shader_source("lit.frag")
    with pytest.raises(ShaderError, match=r"nope\.glsl"):
        shader_source("nope.glsl")


def test_eight_cameras_look_at_the_kit(kit) -> None:  # type: ignore[no-untyped-def]
    cams = kit_cameras(kit)
    assert tuple(cams) == CAMERA_NAMES and len(CAMERA_NAMES) == 8
    for cam in cams.values():
        clip = cam.view_projection(16 / 9) @ np.array([*cam.target, 1.0])
        assert np.allclose(clip[:2] / clip[3], 0.0, atol=1e-5), cam.name
        assert -1 < clip[2] / clip[3] < 1
    with pytest.raises(CameraError, match="stage"):
        pick_camera(kit, "balcony")


def test_camera_move_swings_around_the_target(kit) -> None:  # type: ignore[no-untyped-def]
    cams = kit_cameras(kit)
    move = CameraMove(cams["front"], cams["back"], t0_s=10.0, duration_s=2.0)
    assert move.at(9.0) == cams["front"]
    assert move.at(12.5) == cams["back"]
    for t in np.linspace(10.0, 12.0, 21):
        cam = move.at(float(t))
        assert np.linalg.norm(np.subtract(cam.eye, cam.target)) > 2.0  # never through the kit
