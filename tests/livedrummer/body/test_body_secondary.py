"""Secondary motion: SMED's head-bob cofactors (fig. 4.13), twist speed cap, sway on beats."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.body.secondary import (
    SecondaryParams,
    azimuth,
    build_torso,
    density_cofactor,
    density_side,
    rate_limited,
    velocity_cofactor,
)

R = 0.025  # SMED's strike range radius


def test_density_of_an_empty_side_is_one_and_rests_near_the_beat_weigh_more() -> None:
    assert density_side(np.zeros(0), 0.2, c=1.0) == 1.0
    # interval w split by two onsets into w1, w2, w3 (fig. 4.13), i counted from the beat
    w, c = 0.2, 1.5
    cuts = np.array([0.05, 0.12])
    w1, w2, w3 = 0.05, 0.07, 0.08
    expect = (w1 / (1 + 0 * c) + w2 / (1 + 1 * c) + w3 / (1 + 2 * c)) / w
    assert density_side(cuts, w, c) == pytest.approx(expect)
    # the same rest weighs more next to the beat than next to the mid-beat
    assert density_side(np.array([0.15]), w, c) > density_side(np.array([0.05]), w, c)
    # c = 0: rests weighted by length only, so any split sums to 1
    assert density_side(cuts, w, 0.0) == pytest.approx(1.0)


def test_figure_4_13_beat_two_bobs_more_than_beat_one() -> None:
    beat = 0.5
    beats = np.array([1.0, 1.5])
    # beat 1: one note in its strike range, both sides divided by onsets;
    # beat 2: three notes in its strike range and nothing in the interval before it
    onsets = np.array([0.82, 1.0, 1.12, 1.2, 1.49, 1.5, 1.51, 1.62])
    vel = np.full(onsets.size, 0.8)  # same velocity everywhere
    v = velocity_cofactor(beats, onsets, vel, R)
    d = density_cofactor(beats, np.full(2, beat), onsets, R, c=1.0)
    assert v[0] == pytest.approx(0.8 * 1.1)  # mean velocity + 10 % per note
    assert v[1] == pytest.approx(0.8 * 1.3)
    assert d[1] == pytest.approx(1.0)  # the empty interval before beat 2
    assert d[0] < 1.0
    assert v[0] * d[0] < v[1] * d[1]


def test_rate_limit_caps_angular_velocity() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.3, 1.0])
    goal = np.array([0.0, 1.0, -1.0, -1.0, 0.5])
    out = rate_limited(t, goal, cap_per_s=2.0)
    speed = np.abs(np.diff(out)) / np.diff(t)
    assert np.all(speed <= 2.0 + 1e-12)
    assert out[0] == 0.0 and out[1] == pytest.approx(0.2) and out[-1] == pytest.approx(0.5)


def test_torso_twists_towards_pieces_within_the_cap_and_sways_on_beats() -> None:
    p = SecondaryParams(twist_cap_deg_s=90.0)
    hand_s = np.array([1.0, 1.1, 1.2, 2.0])
    targets = np.array([[0.6, 0.5, 1.0], [-0.4, 0.4, 0.9], [0.6, 0.5, 1.0], [0.0, 0.5, 0.6]])
    torso = build_torso(
        p,
        0.5,
        np.radians(3),
        np.radians(6),
        np.arange(0.0, 3.0, 0.5),
        hand_s,
        targets,
        np.array([0, 0, 1.3]),
        np.zeros(0),
        np.zeros(0),
        hand_s,
    )
    t = np.linspace(0, 3, 3001)
    tw = torso.twist(t)
    assert np.max(np.abs(np.diff(tw)) / np.diff(t)) <= np.radians(90.0) + 1e-9
    assert azimuth(targets[:1])[0] < 0  # a piece to the right turns clockwise (negative)
    assert tw[np.searchsorted(t, 1.0)] < 0
    locals_ = torso.locals(np.array([0.5, 0.75]))
    # sway: leaning further forward on the beat than at mid-beat
    lb = locals_["lower_back"]
    assert abs(lb[0, 1]) > abs(lb[1, 1]) - 1e-12
