"""The built-in character (pure logic): a valid skinned mesh that follows the body's proportions."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.avatar.character import (
    EYE_WHITE,
    HAIR,
    IRIS,
    MATERIALS,
    SHIRT,
    SHOES,
    SKIN,
    TROUSERS,
    build_character,
    chain_weights,
    rest_positions,
)
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.fk import forward
from livedrummer.body.skeleton import (
    JOINTS,
    N_JOINTS,
    PARENTS,
    J,
    SegmentLengths,
    build_skeleton,
)
from livedrummer.render.body_scene import world_rotations

AVATAR = build_character()


def bone_gap(points: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest bone segment (parent joint to joint)."""
    best = np.full(points.shape[0], np.inf)
    for j in range(1, N_JOINTS):
        a, b = joints[PARENTS[j]], joints[j]
        d = b - a
        t = np.clip((points - a) @ d / max(float(d @ d), 1e-12), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * d), axis=1))
    return best


def material_vertices(material: int) -> np.ndarray:
    mesh = AVATAR.mesh
    prim = next(p for p in mesh.primitives if p.material == material)
    return np.unique(mesh.indices[prim.first : prim.first + prim.count])


def test_the_character_is_a_valid_mesh_bound_in_the_rest_pose() -> None:
    mesh = AVATAR.mesh
    mesh.check()
    assert AVATAR.source == "built-in"
    assert len(AVATAR.digest) == 16
    assert 5_000 < mesh.triangle_count < 60_000
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-4)
    # bind = the rest pose: pure translations to the rest joint positions
    rest = rest_positions(SegmentLengths())
    assert np.allclose(mesh.bind[:, :3, :3], np.eye(3))
    assert np.allclose(mesh.bind[:, :3, 3], rest, atol=1e-6)
    assert {m.name for m in mesh.materials} >= {
        "skin",
        "shirt",
        "trousers",
        "shoes",
        "hair",
        "eye_white",
        "iris",
        "lips",
    }
    for material in (SKIN, SHIRT, TROUSERS, SHOES, HAIR, EYE_WHITE, IRIS):
        assert material_vertices(material).size > 0, MATERIALS[material].name
    colours = {m.base_color for m in MATERIALS}
    assert len(colours) == len(MATERIALS)  # every material is a distinct colour


def test_the_body_is_where_the_skeleton_is() -> None:
    """Height, parts and sides: shoes at the feet, hair on top, eyes in front of the head."""
    mesh = AVATAR.mesh
    rest = rest_positions(SegmentLengths())
    p = mesh.positions
    top = p[:, 2].max()
    assert top == pytest.approx(rest[J["head_top"], 2], abs=0.04)
    shoes = p[material_vertices(SHOES)]
    assert shoes[:, 2].min() < rest[J["r_ankle"], 2] - 0.06
    assert shoes[:, 1].max() > rest[J["r_toe"], 1]  # the toes point forward (+y)
    hair = p[material_vertices(HAIR)]
    assert hair[:, 2].max() == pytest.approx(top, abs=1e-6)
    eyes = p[material_vertices(EYE_WHITE)]
    head = rest[J["head"]]
    assert (eyes[:, 1] > head[1] + 0.06).all()  # on the face, which looks along +y
    assert np.sort(np.sign(eyes[:, 0])).tolist().count(1.0) == eyes.shape[0] // 2
    # Standing height: the soles to the crown is an adult's ~1.8 m
    assert top - p[:, 2].min() == pytest.approx(1.8, abs=0.08)


def test_weights_pass_smoothly_across_elbows_and_knees() -> None:
    """At the elbow and knee the skin is shared by both bones; weights change gradually."""
    s = np.linspace(0.0, 0.6, 601)
    w = chain_weights(s, [J["r_shoulder"], J["r_elbow"], J["r_wrist"]], [(0.3, 0.05), (0.57, 0.02)])
    assert np.allclose(w.sum(axis=1), 1.0)
    elbow = w[:, J["r_elbow"]]
    assert elbow[0] == 0 and elbow[300] == pytest.approx(0.5) and w[-1, J["r_wrist"]] == 1
    assert np.abs(np.diff(elbow[:450])).max() < 0.02  # per millimetre
    mesh = AVATAR.mesh
    rest = rest_positions(SegmentLengths())
    dense = np.zeros((mesh.vertex_count, N_JOINTS))
    np.put_along_axis(dense, mesh.joints.astype(np.int64), mesh.weights, axis=1)
    for parent, joint in (("r_shoulder", "r_elbow"), ("l_hip", "l_knee")):
        ring = np.abs(mesh.positions[:, 2] - rest[J[joint], 2]) < 0.03
        ring &= np.linalg.norm(mesh.positions[:, :2] - rest[J[joint], :2], axis=1) < 0.1
        assert ring.sum() > 10, joint
        share = dense[ring][:, [J[parent], J[joint]]]
        assert np.allclose(share.sum(axis=1), 1.0, atol=1e-5)
        assert (share.min(axis=1) > 0.2).all(), joint


def test_the_character_follows_the_proportions() -> None:
    tall = SegmentLengths(thigh=0.52, shin=0.50, upper_arm=0.34, forearm=0.30)
    a = build_character(tall)
    assert a.lengths == tall
    assert a.digest != AVATAR.digest
    rest = rest_positions(tall)
    assert np.allclose(a.mesh.bind[:, :3, 3], rest, atol=1e-6)
    height = np.ptp(a.mesh.positions[:, 2])
    assert height > np.ptp(AVATAR.mesh.positions[:, 2]) + 0.1


def test_a_played_pose_keeps_hands_on_the_sticks_and_shoes_on_the_feet() -> None:
    """Skin the character in a bent pose (numpy reference): the fingers stay round the grip,
    the shoes round the ankle, the head round the head joint: nothing flies off."""
    sk = build_skeleton()
    local = np.tile([1.0, 0.0, 0.0, 0.0], (1, N_JOINTS, 1))
    x = np.array([1.0, 0.0, 0.0])
    local[0, J["r_shoulder"]] = quat.from_axis_angle(x, -1.0)
    local[0, J["r_elbow"]] = quat.from_axis_angle(x, -1.6)
    local[0, J["r_stick"]] = quat.from_axis_angle(np.array([0.0, 1.0, 0.0]), 0.4)
    local[0, J["r_hip"]] = quat.from_axis_angle(x, -1.3)
    local[0, J["r_knee"]] = quat.from_axis_angle(x, 1.4)
    wq, wp = forward(sk, local, sk.root_m[None])
    np.testing.assert_allclose(world_rotations(local)[0], wq[0], atol=1e-6)
    mesh = AVATAR.mesh
    out, _ = skin(mesh, skin_matrices(joint_matrices(wq[0], wp[0]), mesh.bind))
    main = mesh.joints[np.arange(mesh.vertex_count), np.argmax(mesh.weights, axis=1)]
    for joint, reach in (("r_stick", 0.07), ("r_ankle", 0.25), ("head", 0.2), ("r_knee", 0.5)):
        near = np.linalg.norm(out[main == J[joint]] - wp[0, J[joint]], axis=1)
        assert near.size and near.max() < reach, joint
    # nothing flies off the skeleton: every vertex stays within a torso's depth of a bone
    rest_p = mesh.bind[:, :3, 3].astype(np.float64)
    assert bone_gap(mesh.positions, rest_p).max() < 0.15
    assert bone_gap(out, wp[0]).max() < 0.18
    assert JOINTS[int(main[np.argmax(out[:, 2])])] in ("head", "neck")
