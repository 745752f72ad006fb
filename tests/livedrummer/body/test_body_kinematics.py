"""Skeleton, quaternions, forward kinematics and the pose layout."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from livedrummer.body import fk, quat
from livedrummer.body.pose import pack_poses, pose_dtype
from livedrummer.body.skeleton import JOINTS, N_JOINTS, PARENTS, build_skeleton

vec = st.tuples(*[st.floats(-3, 3, allow_nan=False) for _ in range(3)])


@given(vec)
def test_exp_log_round_trip(v: tuple[float, float, float]) -> None:
    rv = np.array(v)
    if np.linalg.norm(rv) >= np.pi - 1e-3:
        rv = rv / np.linalg.norm(rv) * (np.pi - 0.01)
    np.testing.assert_allclose(quat.log(quat.exp(rv)), rv, atol=1e-9)


@given(vec, vec, vec)
def test_rotation_matches_matrix_and_composes(a: tuple, b: tuple, v: tuple) -> None:
    qa, qb = quat.exp(np.array(a)), quat.exp(np.array(b))
    p = np.array(v)
    np.testing.assert_allclose(quat.rotate(qa, p), quat.to_matrix(qa) @ p, atol=1e-9)
    np.testing.assert_allclose(
        quat.rotate(quat.mul(qa, qb), p), quat.rotate(qa, quat.rotate(qb, p)), atol=1e-9
    )
    back = quat.from_matrix(quat.to_matrix(qa))
    assert min(np.abs(back - qa).max(), np.abs(back + qa).max()) < 1e-9


def test_align_maps_direction_and_side() -> None:
    rng = np.random.default_rng(1)
    d = rng.normal(size=(50, 3))
    side = rng.normal(size=(50, 3))
    q = quat.align(np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0]), d, side)
    got = quat.rotate(q, np.array([0.0, 0.0, -1.0]))
    np.testing.assert_allclose(got, d / np.linalg.norm(d, axis=1, keepdims=True), atol=1e-9)
    x = quat.rotate(q, np.array([1.0, 0.0, 0.0]))
    assert np.all(np.sum(x * side, axis=1) > 0)
    np.testing.assert_allclose(np.sum(x * got, axis=1), 0.0, atol=1e-9)


def test_rest_pose_positions_are_summed_offsets() -> None:
    skel = build_skeleton(seat_height_m=0.5)
    local = quat.identity((3, N_JOINTS))
    root = np.tile(skel.root_m, (3, 1))
    _, pos = fk.forward(skel, local, root)
    for j in range(N_JOINTS):
        expect = skel.root_m.copy()
        k = j
        while k > 0:
            expect += skel.offsets[k]
            k = PARENTS[k]
        np.testing.assert_allclose(pos[:, j], np.tile(expect, (3, 1)), atol=1e-12)
    # arms hang: the right stick tip is straight below the right shoulder
    tip, sh = pos[0, JOINTS.index("r_tip")], pos[0, JOINTS.index("r_shoulder")]
    assert tip[0] == sh[0] and tip[2] < sh[2]


def test_fk_rotation_turns_children_only() -> None:
    skel = build_skeleton()
    local = quat.identity((1, N_JOINTS))
    elbow = JOINTS.index("r_elbow")
    local[0, elbow] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2)
    _, rest = fk.forward(skel, quat.identity((1, N_JOINTS)), skel.root_m[None])
    _, bent = fk.forward(skel, local, skel.root_m[None])
    moved = np.linalg.norm(bent - rest, axis=-1)[0] > 1e-9
    assert [JOINTS[j] for j in np.flatnonzero(moved)] == ["r_wrist", "r_stick", "r_tip"]
    # the forearm now points forward (+y): a quarter turn about +x
    fore = bent[0, JOINTS.index("r_wrist")] - bent[0, elbow]
    np.testing.assert_allclose(fore / np.linalg.norm(fore), [0, 1, 0], atol=1e-12)


@settings(max_examples=20)
@given(st.integers(1, 40))
def test_to_local_inverts_forward(n: int) -> None:
    skel = build_skeleton()
    rng = np.random.default_rng(n)
    local = quat.exp(rng.normal(scale=0.8, size=(n, N_JOINTS, 3)))
    wq, _ = fk.forward(skel, local, np.tile(skel.root_m, (n, 1)))
    back = fk.to_local(wq)
    dots = np.abs(np.sum(back * local, axis=-1))
    np.testing.assert_allclose(dots, 1.0, atol=1e-9)


def test_pose_dtype_layout_is_packed_float32() -> None:
    dt = pose_dtype(10)
    assert dt.itemsize == 4 * (1 + N_JOINTS * 4 + N_JOINTS * 3 + 3 * 10)
    assert all(dt[name].base == np.dtype("<f4") for name in dt.names)
    assert dt.names == ("time_s", "rotation", "position", "swing", "lift", "glow")
    offsets = [dt.fields[name][1] for name in dt.names]
    assert offsets == sorted(offsets) and offsets[0] == 0
    t = np.array([0.5, 1.0])
    poses = pack_poses(
        t,
        quat.identity((2, N_JOINTS)),
        np.ones((2, N_JOINTS, 3)),
        np.zeros((2, 10)),
        np.zeros((2, 10)),
        np.full((2, 10), 0.25),
    )
    raw = poses.tobytes()
    again = np.frombuffer(raw, dtype=dt)
    assert again["glow"][1, 3] == np.float32(0.25) and again["time_s"][1] == 1.0
