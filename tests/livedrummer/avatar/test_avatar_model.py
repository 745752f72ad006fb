"""The avatar contract and the numpy skinning reference (pure logic)."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.avatar.model import Avatar, AvatarError, Material, Primitive, SkinnedMesh
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.fk import forward
from livedrummer.body.skeleton import N_JOINTS, J, SegmentLengths, build_skeleton


def rest_bind() -> np.ndarray:
    sk = build_skeleton()
    _, p = forward(sk, np.tile([1.0, 0, 0, 0], (1, N_JOINTS, 1)), sk.root_m[None])
    return joint_matrices(np.tile([1.0, 0, 0, 0], (N_JOINTS, 1)), p[0]).astype(np.float32)


def mesh(positions: np.ndarray, joints: np.ndarray, weights: np.ndarray) -> SkinnedMesh:
    v = positions.shape[0]
    return SkinnedMesh(
        positions=positions.astype(np.float32),
        normals=np.tile(np.float32([0, 0, 1]), (v, 1)),
        uv=np.zeros((v, 2), np.float32),
        joints=joints.astype(np.uint16),
        weights=weights.astype(np.float32),
        indices=np.arange(3, dtype=np.uint32) % v,
        primitives=(Primitive(0, 0, 3),),
        materials=(Material("skin"),),
        bind=rest_bind(),
    )


def test_a_vertex_weighted_to_one_joint_follows_it_rigidly() -> None:
    sk = build_skeleton()
    bind = rest_bind()
    elbow = bind[J["r_elbow"], :3, 3]
    points = elbow + np.array([[0.02, 0.0, -0.1], [0.0, 0.03, -0.2], [0.0, 0.0, 0.0]])
    m = mesh(points, np.tile([J["r_elbow"], 0, 0, 0], (3, 1)), np.tile([1.0, 0, 0, 0], (3, 1)))
    m.check()
    local = np.tile([1.0, 0, 0, 0], (1, N_JOINTS, 1))
    local[0, J["r_shoulder"]] = quat.from_axis_angle(np.array([1.0, 0, 0]), 1.1)
    local[0, J["r_elbow"]] = quat.from_axis_angle(np.array([0, 1.0, 0]), 0.7)
    wq, wp = forward(sk, local, sk.root_m[None])
    out, _ = skin(m, skin_matrices(joint_matrices(wq[0], wp[0]), m.bind))
    expect = wp[0, J["r_elbow"]] + quat.rotate(wq[0, J["r_elbow"]], points - elbow)
    assert np.abs(out - expect).max() < 1e-5


def test_two_joint_weights_blend_linearly() -> None:
    bind = rest_bind()
    p = bind[J["r_wrist"], :3, 3][None]
    m = mesh(
        np.repeat(p, 3, 0),
        np.tile([J["r_wrist"], J["r_elbow"], 0, 0], (3, 1)),
        np.tile([0.25, 0.75, 0, 0], (3, 1)),
    )
    world = bind.astype(np.float64).copy()
    world[J["r_wrist"], :3, 3] += (0.1, 0.0, 0.0)
    world[J["r_elbow"], :3, 3] += (0.0, 0.2, 0.0)
    out, _ = skin(m, skin_matrices(world, bind))
    assert np.allclose(out[0], p[0] + (0.025, 0.15, 0.0), atol=1e-6)


def test_bad_meshes_are_named() -> None:
    good = mesh(np.zeros((3, 3)), np.zeros((3, 4)), np.tile([1.0, 0, 0, 0], (3, 1)))
    with pytest.raises(AvatarError, match="weights sum"):
        mesh(np.zeros((3, 3)), np.zeros((3, 4)), np.tile([0.5, 0, 0, 0], (3, 1))).check()
    with pytest.raises(AvatarError, match="joint index"):
        mesh(np.zeros((3, 3)), np.full((3, 4), 99), np.tile([1.0, 0, 0, 0], (3, 1))).check()
    a = Avatar("t", "built-in", SegmentLengths(), good)
    assert len(a.digest) == 16
    assert Avatar("t", "built-in", SegmentLengths(thigh=0.5), good).digest != a.digest
