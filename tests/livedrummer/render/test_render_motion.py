"""Body poses mapped to the scene's kit channels and sticks, and the window's transport (pure)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from livedrummer.body.animation import FOOT_LIFT_M
from livedrummer.body.channels import BEATER_MAX_RAD, PEDAL_MAX_RAD
from livedrummer.body.pose import pose_dtype
from livedrummer.body.skeleton import JOINTS, PARENTS, J
from livedrummer.kit.behaviour import footboard_angle
from livedrummer.kit.loader import load_kit
from livedrummer.render.body_scene import (
    BODY_SKELETON,
    STICK_TAIL_M,
    scene_channels,
    stick_segments,
)
from livedrummer.render.scene import (
    CH_HIGHLIGHT,
    CH_PEDAL,
    CH_TRAVEL,
    CH_WOBBLE,
    CH_WOBBLE_AZIMUTH,
    N_CHANNELS,
)
from livedrummer.render.transport import KEYS, SPEEDS, Transport

KIT = load_kit("rock5")
P = {p.name: i for i, p in enumerate(KIT.pieces)}


def records(n: int, seed: int = 0) -> np.ndarray:
    """Pose records with random, distinct values in every channel."""
    rng = np.random.default_rng(seed)
    out = np.zeros(n, pose_dtype(len(KIT.pieces)))
    for field in ("swing", "lift", "glow"):
        out[field] = rng.uniform(0.1, 1.0, out[field].shape)
    out["position"] = rng.normal(size=out["position"].shape)
    return out


def test_scene_skeleton_is_the_body_skeleton() -> None:
    assert BODY_SKELETON.names == JOINTS
    assert BODY_SKELETON.parent.tolist() == list(PARENTS)
    # the stick tips are drawn as sticks, not as limbs
    for tip in ("r_tip", "l_tip"):
        assert BODY_SKELETON.segment_radius_m[J[tip]] == 0
        assert BODY_SKELETON.joint_radius_m[J[tip]] == 0
    drawn = BODY_SKELETON.bones[BODY_SKELETON.segment_radius_m[BODY_SKELETON.bones] > 0]
    assert len(drawn) == len(JOINTS) - 1 - 2


def test_channels_follow_the_body_channels() -> None:
    rec = records(5)
    ch = scene_channels(rec, KIT)
    assert ch.shape == (5, len(KIT.pieces), N_CHANNELS) and ch.dtype == np.float32
    np.testing.assert_array_equal(ch[..., CH_HIGHLIGHT], rec["glow"])
    for name, piece in P.items():
        kind = KIT.pieces[piece].kind
        wobble, travel = ch[:, piece, CH_WOBBLE], ch[:, piece, CH_TRAVEL]
        board = ch[:, piece, CH_PEDAL]
        swing = rec["swing"][:, piece]
        if kind.value == "kick":  # the beater's angle back from the head
            np.testing.assert_array_equal(travel, swing)
            assert np.all(wobble == 0)
            foot = swing / BEATER_MAX_RAD
            np.testing.assert_allclose(board, footboard_angle(FOOT_LIFT_M * foot), atol=1e-6)
        elif kind.value == "hihat":  # top cymbal's lift; the board follows the foot
            np.testing.assert_array_equal(travel, rec["lift"][:, piece])
            assert np.all(wobble == 0)
            foot = swing / PEDAL_MAX_RAD
            np.testing.assert_allclose(board, footboard_angle(FOOT_LIFT_M * foot), atol=1e-6)
        elif kind.value in ("tom", "snare") or kind.is_cymbal:  # swing or shake when struck
            np.testing.assert_array_equal(wobble, swing)
            assert np.all(travel == 0) and np.all(board == 0), name
        else:
            assert np.all(wobble == 0) and np.all(travel == 0), name
        if kind.value in ("kick", "hihat"):
            assert np.all(board > 0), name


def test_cymbal_wobble_dips_the_edge_nearest_the_drummer() -> None:
    rec = records(1)
    az = scene_channels(rec, KIT)[0, :, CH_WOBBLE_AZIMUTH]
    for k, piece in enumerate(KIT.pieces):
        axis = np.array([np.cos(az[k]), np.sin(az[k]), 0.0])
        to_seat = -np.array(piece.position_m) * [1, 1, 0]
        # a small positive turn about the axis moves the seat-side edge down
        assert np.cross(axis, to_seat)[2] < 0, piece.name


def test_sticks_run_from_behind_the_grip_to_the_tip() -> None:
    rec = records(3)
    sticks = stick_segments(rec["position"])
    assert sticks.shape == (3, 2, 2, 3) and sticks.dtype == np.float32
    for k, side in enumerate("rl"):
        grip, tip = rec["position"][:, J[f"{side}_stick"]], rec["position"][:, J[f"{side}_tip"]]
        np.testing.assert_allclose(sticks[:, k, 1], tip, atol=1e-6)
        back = sticks[:, k, 0] - grip
        np.testing.assert_allclose(np.linalg.norm(back, axis=1), STICK_TAIL_M, atol=1e-5)
        cos = np.sum(back * (grip - tip), axis=1) / np.linalg.norm(back * 1, axis=1)
        np.testing.assert_allclose(cos / np.linalg.norm(grip - tip, axis=1), 1.0, atol=1e-5)


def test_transport_plays_pauses_and_stops_at_the_end() -> None:
    tr = Transport(duration_s=10.0)
    assert tr.advance(1.0) == 0.0  # paused
    tr.apply("play_pause")
    assert tr.advance(2.5) == pytest.approx(2.5)
    tr.apply("faster")
    assert tr.speed == SPEEDS[SPEEDS.index(1.0) + 1]
    tr.advance(100.0)
    assert tr.position_s == 10.0 and not tr.playing
    tr.apply("play_pause")  # from the end: starts over
    assert tr.position_s == 0.0 and tr.playing


def test_transport_reverse_step_seek_and_markers() -> None:
    tr = Transport(duration_s=20.0, step_s=0.1)
    tr.seek(5.0)
    tr.apply("reverse")
    tr.apply("play_pause")
    assert tr.advance(1.0) == pytest.approx(4.0)
    tr.apply("step_forward")
    assert not tr.playing and tr.position_s == pytest.approx(4.1)
    tr.apply("mark")
    tr.apply("seek_forward")
    tr.apply("mark")
    tr.apply("to_start")
    tr.apply("next_mark")
    assert tr.position_s == pytest.approx(4.1)
    tr.apply("next_mark")
    assert tr.position_s == pytest.approx(9.1)
    tr.apply("previous_mark")
    assert tr.position_s == pytest.approx(4.1)
    tr.apply("previous_mark")
    assert tr.position_s == pytest.approx(4.1)  # no earlier marker: stays
    for _ in range(20):
        tr.apply("slower")
    assert tr.speed == SPEEDS[0]
    tr.apply("normal_speed")
    assert tr.speed == 1.0


def test_every_key_names_an_action() -> None:
    tr = Transport(duration_s=3.0)
    for action in set(KEYS.values()):
        tr.apply(action)
    with pytest.raises(KeyError):
        tr.apply("explode")


@given(st.lists(st.tuples(st.sampled_from(sorted(set(KEYS.values()))),
                          st.floats(0, 5)), max_size=40))  # fmt: skip
def test_transport_position_stays_in_range(steps: list[tuple[str, float]]) -> None:
    tr = Transport(duration_s=7.0)
    for action, dt in steps:
        tr.apply(action)
        tr.advance(dt)
        assert 0.0 <= tr.position_s <= 7.0
