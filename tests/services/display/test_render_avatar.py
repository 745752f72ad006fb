"""The skinned avatar on a real OpenGL context (EGL; llvmpipe without a GPU).

GPU skinning is read back by transform feedback and compared with the numpy reference; the
drawn character is checked in pixels (its silhouette, its face from the front camera); the
front and stage cameras frame the drummer and the kit; glTF alpha modes and textures draw
as specified.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from livedrummer.avatar.character import EYE_WHITE, IRIS, SKIN, build_character
from livedrummer.avatar.model import Avatar, Material, Primitive, SkinnedMesh
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.skeleton import N_JOINTS, J, SegmentLengths
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, kit_cameras
from livedrummer.render.kitmesh import KitMesh, build_kit_mesh, empty_stage
from livedrummer.render.scene import SceneFrame, empty_channels
from livedrummer.timeline.performance import Performance
from services.display.context import DisplayError, headless_context
from services.display.renderer import BACKGROUND, Renderer

W, H = 480, 270
AVATAR = build_character()
BG = np.round(np.array(BACKGROUND) * 255).astype(int)


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def scene(groove: Performance) -> BodyScene:
    from livedrummer.midi.notemap import load_note_map
    from services.cli.files import DEMO_MAP

    return BodyScene.perform(groove, load_kit("rock5"), load_note_map(DEMO_MAP))


def project(cam: Camera, points: np.ndarray, size: tuple[int, int] = (W, H)) -> np.ndarray:
    """World points (N, 3) to pixel (x right, y down) coordinates (N, 2)."""
    w, h = size
    clip = np.c_[points, np.ones(len(points))] @ cam.view_projection(w / h).T.astype(np.float64)
    ndc = clip[:, :2] / clip[:, 3:4]
    out: np.ndarray = np.c_[(ndc[:, 0] + 1) / 2 * w, (1 - ndc[:, 1]) / 2 * h]
    return out


def floor_only(km: KitMesh) -> KitMesh:
    """The same stage floor (same lighting centre) without the kit's pieces."""
    keep = km.mesh == "floor"
    names = (
        "mesh",
        "model",
        "color",
        "material",
        "highlight_weight",
        "piece",
        "motion",
        "pivot",
        "axis",
    )
    return dataclasses.replace(km, **{n: getattr(km, n)[keep] for n in names})


def alone(frame: SceneFrame) -> SceneFrame:
    """The drummer of ``frame`` on an empty stage, sticks hidden below the floor."""
    away = np.zeros((2, 2, 3), np.float32)
    away[..., 2] = -1.0
    return SceneFrame(frame.joints_m, away, empty_channels(0), frame.time_s, frame.rotations_q)


def reference(avatar: Avatar, frame: SceneFrame) -> np.ndarray:
    assert frame.rotations_q is not None
    world = joint_matrices(frame.rotations_q, frame.joints_m)
    return skin(avatar.mesh, skin_matrices(world, avatar.mesh.bind))[0]


def test_frames_carry_world_rotations(scene: BodyScene) -> None:
    frame = scene.frame_at(2.0)
    assert frame.rotations_q is not None and frame.rotations_q.shape == (N_JOINTS, 4)
    frame.check(BODY_SKELETON, len(scene.kit.pieces))
    assert np.allclose(np.linalg.norm(frame.rotations_q, axis=1), 1.0, atol=1e-5)


def test_gpu_skinning_equals_the_numpy_reference(ctx: Any, scene: BodyScene) -> None:
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (64, 64), samples=0)
    assert r.skinned is not None
    for t in (1.0, 2.05, 3.3):
        frame = scene.frame_at(t)
        assert frame.rotations_q is not None
        gpu = r.skinned.skinned_positions(frame.rotations_q, frame.joints_m)
        cpu = reference(r.skinned.avatar, frame)
        assert np.abs(gpu - cpu).max() < 1e-4
        assert np.abs(gpu - r.skinned.avatar.mesh.positions).max() > 0.1  # it did move


def test_a_vertex_weighted_to_one_joint_follows_it_exactly(ctx: Any, scene: BodyScene) -> None:
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (64, 64), samples=0)
    assert r.skinned is not None
    mesh = AVATAR.mesh
    frame = scene.frame_at(2.05)
    assert frame.rotations_q is not None
    gpu = r.skinned.skinned_positions(frame.rotations_q, frame.joints_m)
    world = joint_matrices(frame.rotations_q, frame.joints_m)
    for joint in ("r_elbow", "l_wrist", "head", "r_ankle"):
        j = J[joint]
        rigid = np.flatnonzero((mesh.joints[:, 0] == j) & (mesh.weights[:, 0] == 1.0))
        assert rigid.size > 20, joint
        local = mesh.positions[rigid] - mesh.bind[j, :3, 3]  # bind is a translation
        expect = local @ world[j, :3, :3].T + world[j, :3, 3]
        assert np.abs(gpu[rigid] - expect).max() < 1e-5, joint


def test_weights_are_renormalised_on_the_gpu(ctx: Any) -> None:
    """Weights that do not sum to one (a loader's rounding) still give a rigid vertex."""
    mesh = AVATAR.mesh
    scaled = dataclasses.replace(mesh, weights=(mesh.weights * 0.9).astype(np.float32))
    avatar = Avatar("scaled", "test", SegmentLengths(), mesh, digest="x")
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (64, 64), samples=0, avatar=avatar)
    assert r.skinned is not None
    r.skinned._vbo.write(  # the shader reads the scaled weights
        np.column_stack(
            [
                scaled.positions,
                scaled.normals,
                scaled.uv,
                scaled.joints.astype(np.float32),
                scaled.weights,
            ]
        ).astype(np.float32)
    )
    rot = np.tile(np.array([1, 0, 0, 0], np.float32), (N_JOINTS, 1))
    pos = mesh.bind[:, :3, 3] + np.array([0.0, 0.0, 0.5], np.float32)
    gpu = r.skinned.skinned_positions(rot, pos)
    assert np.abs(gpu - (mesh.positions + np.array([0, 0, 0.5], np.float32))).max() < 1e-5


def test_the_silhouette_covers_the_skinned_mesh(ctx: Any, scene: BodyScene) -> None:
    """Pixels drawn = the numpy-skinned triangles rasterised on the CPU (front view)."""
    kit = scene.kit
    cam = kit_cameras(kit)["front"]
    frame = alone(scene.frame_at(2.05))
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (W, H), samples=0, shadows=False)
    r.draw(frame, cam)
    drawn = np.abs(r.read_rgb().astype(int) - empty_view(ctx, cam)).sum(-1) > 6
    pts = project(cam, reference(AVATAR, frame).astype(np.float64))
    expect = rasterise(pts, AVATAR.mesh.indices.reshape(-1, 3))
    assert expect.sum() > 0.04 * W * H  # a drummer, not a speck
    union = (drawn | expect).sum()
    assert (drawn & expect).sum() / union > 0.95
    # the rest pose does not cover it: the skinning moved the mesh
    rest = rasterise(
        project(cam, AVATAR.mesh.positions.astype(np.float64)), AVATAR.mesh.indices.reshape(-1, 3)
    )
    assert (rest & expect).sum() / (rest | expect).sum() < 0.8


def empty_view(ctx: Any, cam: Camera) -> np.ndarray:
    r = Renderer(ctx, empty_stage(), None, (W, H), samples=0)
    r.draw(None, cam)
    return r.read_rgb().astype(int)


def rasterise(pts: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Pixel centres covered by any of the 2D triangles (H, W) bool."""
    mask = np.zeros((H, W), bool)
    for a, b, c in pts[tri]:
        x0, x1 = (
            int(max(np.floor(min(a[0], b[0], c[0])), 0)),
            int(min(max(a[0], b[0], c[0]), W - 1)),
        )
        y0, y1 = (
            int(max(np.floor(min(a[1], b[1], c[1])), 0)),
            int(min(max(a[1], b[1], c[1]), H - 1)),
        )
        if x1 < x0 or y1 < y0:
            continue
        ys, xs = np.mgrid[y0 : y1 + 1, x0 : x1 + 1] + 0.5
        d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        if abs(d) < 1e-12:
            continue
        u = ((xs - a[0]) * (c[1] - a[1]) - (ys - a[1]) * (c[0] - a[0])) / d
        v = ((ys - a[1]) * (b[0] - a[0]) - (xs - a[0]) * (b[1] - a[1])) / d
        mask[y0 : y1 + 1, x0 : x1 + 1] |= (u >= 0) & (v >= 0) & (u + v <= 1)
    return mask


def material_centres(frame: SceneFrame, material: int) -> np.ndarray:
    """Skinned centre of each connected blob of ``material`` (left and right eye ...)."""
    mesh = AVATAR.mesh
    prim = next(p for p in mesh.primitives if p.material == material)
    verts = np.unique(mesh.indices[prim.first : prim.first + prim.count])
    posed = reference(AVATAR, frame)[verts]
    side = mesh.positions[verts, 0] > mesh.bind[J["head"], 0, 3]
    return np.array([posed[side].mean(axis=0), posed[~side].mean(axis=0)])


def test_the_face_is_visible_from_the_front(ctx: Any, scene: BodyScene) -> None:
    kit = scene.kit
    size = (960, 540)
    cam = kit_cameras(kit)["front"]
    frame = scene.frame_at(2.05)
    r = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0)
    r.draw(frame, cam)
    img = r.read_rgb().astype(int)
    for material, looks in ((EYE_WHITE, "white"), (IRIS, "iris")):
        for x, y in project(cam, material_centres(frame, material), size).astype(int):
            patch = img[y - 2 : y + 3, x - 2 : x + 3].reshape(-1, 3)
            if looks == "white":  # bright and grey: the white of an eye, not skin or hair
                ok = (patch.min(axis=1) > 110) & (np.ptp(patch, axis=1) < 60)
            else:  # the iris is bluer than skin
                ok = patch[:, 2] > patch[:, 0]
            assert ok.any(), (looks, x, y)
    # between the eyes and on the forehead: skin, warm and lit
    eyes = material_centres(frame, EYE_WHITE)
    assert frame.rotations_q is not None
    up = quat.rotate(frame.rotations_q[J["head"]].astype(np.float64), np.array([0.0, 0, 1]))
    for point in (eyes.mean(axis=0), eyes.mean(axis=0) + 0.03 * up):
        x, y = project(cam, point[None], size)[0].astype(int)
        rgb = img[y, x]
        assert rgb[0] > rgb[2] + 40 and rgb[0] > 90, rgb
    assert SKIN == 0


@pytest.mark.parametrize("kit_name", ["rock5", "rock5-left"])
@pytest.mark.parametrize("camera", ["front", "stage"])
def test_front_and_stage_frame_drummer_and_kit(
    ctx: Any, scene: BodyScene, groove: Performance, kit_name: str, camera: str
) -> None:
    from livedrummer.midi.notemap import load_note_map
    from services.cli.files import DEMO_MAP

    kit: Kit = load_kit(kit_name)
    body = scene if kit_name == "rock5" else BodyScene.perform(groove, kit, load_note_map(DEMO_MAP))
    km = build_kit_mesh(kit)
    cam = kit_cameras(kit)[camera]
    r = Renderer(ctx, km, BODY_SKELETON, (W, H), samples=0, shadows=False)  # objects, not shadows
    r.draw(body.frame_at(2.05), cam)
    img = r.read_rgb().astype(int)
    e = Renderer(ctx, floor_only(km), None, (W, H), samples=0)
    e.draw(None, cam)
    mask = np.abs(img - e.read_rgb().astype(int)).sum(-1) > 30
    rows = np.flatnonzero(mask.any(axis=1))
    assert (rows.max() - rows.min() + 1) / H >= 0.6
    assert rows.min() > 0  # the cymbals and the head are not cut off at the top


def test_the_mannequin_stays_selectable(ctx: Any, scene: BodyScene) -> None:
    kit = scene.kit
    cam = kit_cameras(kit)["front"]
    frame = alone(scene.frame_at(2.05))
    images = []
    for avatar in (None, "mannequin"):
        r = Renderer(ctx, empty_stage(), BODY_SKELETON, (W, H), samples=0, avatar=avatar)
        assert (r.skinned is None) == (avatar == "mannequin")
        r.draw(frame, cam)
        images.append(r.read_rgb().astype(int))
    empty = empty_view(ctx, cam)
    drawn = [np.abs(i - empty).sum(-1) > 6 for i in images]
    assert drawn[0].sum() > 0.04 * W * H and drawn[1].sum() > 0.02 * W * H
    # two different figures: over 12 % of the figure's pixels differ (15 % with the kit-box
    # framing, 13 % with the figure framing, which draws the whole body a little smaller)
    assert (drawn[0] != drawn[1]).sum() > 0.12 * drawn[1].sum()
    # a frame without rotations (a test's stand-in pose) is drawn as capsules
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (W, H), samples=0)
    r.draw(dataclasses.replace(frame, rotations_q=None), cam)
    assert np.array_equal(r.read_rgb().astype(int), images[1])


def test_the_drummer_casts_the_key_lights_shadow(ctx: Any, scene: BodyScene) -> None:
    """Seen from above, the stage floor darkens beside the drummer, on the side away from the
    key light (which hangs in front, to the drummer's right: the shadow falls back and left
    in the picture's terms, +x and -y in the kit's)."""
    cam = kit_cameras(scene.kit)["overhead"]
    frame = alone(scene.frame_at(2.05))
    images = {}
    for on in (True, False):
        r = Renderer(ctx, empty_stage(), BODY_SKELETON, (W, H), samples=0, shadows=on)
        r.draw(frame, cam)
        images[on] = r.read_rgb().astype(int)
    dark = (images[False] - images[True]).sum(-1) > 15
    assert dark.sum() > 0.01 * W * H
    ys, xs = np.nonzero(dark)
    px, py = project(cam, frame.joints_m[[J["pelvis"]]].astype(np.float64))[0]
    assert xs.mean() > px and ys.mean() > py  # screen right is +x, screen down is -y


def quad_avatar(materials: tuple[Material, ...], depth_y: tuple[float, ...]) -> Avatar:
    """One square per material, 0.6 m wide, facing +y at heights around 1 m, on the pelvis."""
    pos, uv, idx, prims = [], [], [], []
    for k, y in enumerate(depth_y):
        base = 4 * k
        # counter-clockwise seen from +y (the camera), where screen-left is world +x
        pos += [(0.3, y, 0.7), (-0.3, y, 0.7), (-0.3, y, 1.3), (0.3, y, 1.3)]
        uv += [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
        prims.append(Primitive(k, 6 * k, 6))
    v = len(pos)
    bind = np.tile(np.eye(4, dtype=np.float32), (N_JOINTS, 1, 1))
    mesh = SkinnedMesh(
        positions=np.array(pos, np.float32),
        normals=np.tile(np.array([0, 1, 0], np.float32), (v, 1)),
        uv=np.array(uv, np.float32),
        joints=np.zeros((v, 4), np.uint16),
        weights=np.tile(np.array([1, 0, 0, 0], np.float32), (v, 1)),
        indices=np.array(idx, np.uint32),
        primitives=tuple(prims),
        materials=materials,
        bind=bind,
    )
    return Avatar("quads", "test", SegmentLengths(), mesh)


def draw_quads(ctx: Any, avatar: Avatar) -> np.ndarray:
    cam = Camera("test", (0.0, 3.0, 1.0), (0.0, 0.0, 1.0), 30.0)
    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (W, H), samples=0, avatar=avatar)
    rot = np.tile(np.array([1, 0, 0, 0], np.float32), (N_JOINTS, 1))
    away = np.full((2, 2, 3), -1.0, np.float32)
    r.draw(SceneFrame(np.zeros((N_JOINTS, 3), np.float32), away, empty_channels(0), 0.0, rot), cam)
    return r.read_rgb().astype(int)


def test_alpha_modes_and_textures(ctx: Any) -> None:
    # texture: left half red and transparent, right half green and opaque
    tex = np.zeros((2, 2, 4), np.uint8)
    tex[:, 0] = (255, 0, 0, 0)
    tex[:, 1] = (0, 255, 0, 255)
    white = (1.0, 1.0, 1.0, 1.0)
    back = Material("back", (0.1, 0.1, 1.0, 1.0), shading="toon")
    mask = Material("mask", white, texture=tex, alpha_mode="MASK", alpha_cutoff=0.5)
    blend = Material("blend", (1.0, 1.0, 1.0, 0.5), alpha_mode="BLEND")
    cx, cy = W // 2, H // 2
    left, right = (cx - 40, cy), (cx + 40, cy)
    img = draw_quads(ctx, quad_avatar((back, mask), (0.0, 0.2)))
    assert img[left[1], left[0], 2] > img[left[1], left[0], 1] + 40  # masked away: blue behind
    assert img[right[1], right[0], 1] > img[right[1], right[0], 2] + 40  # textured green
    opaque = draw_quads(ctx, quad_avatar((back,), (0.0,)))
    half = draw_quads(ctx, quad_avatar((back, blend), (0.0, 0.2)))
    # blended white over blue: brighter than blue alone, yet the blue still shows through
    b, h = opaque[cy, cx], half[cy, cx]
    assert h[0] > b[0] + 30 and h[2] > h[0] - 5 and h[2] >= b[2]
    # drawn after the opaque ones even when listed first: the blue behind is still seen
    first = draw_quads(ctx, quad_avatar((blend, back), (0.2, 0.0)))
    assert np.abs(first[cy, cx] - h).max() <= 2
    assert not np.array_equal(BG, b)
