"""Kit channels: cymbal decay and override, choke, hi-hat height from CC4, beater, glow."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from livedrummer.body.animation import hihat_openness
from livedrummer.body.channels import (
    BEATER_LENGTH_M,
    VibrationParams,
    beater_tip,
    glow,
    kit_channels,
    vibration,
)
from livedrummer.body.targets import HIHAT_MAX_LIFT_M, zone_target
from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import Zone
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind

V = VibrationParams(max_angle_rad=0.2, eta=0.05, beta=2 * np.pi * 4)


def test_cymbal_follows_a_decaying_sinusoid_from_the_hit() -> None:
    t = np.array([0.5, 1.0, 1.03, 1.3, 2.0])
    got = vibration(t, np.array([1.0]), np.array([0.5]), np.zeros(0), V)
    dt = t - 1.0
    expect = np.where(dt >= 0, 0.5 * 0.2 * 0.05**dt * np.sin(V.beta * dt), 0.0)
    np.testing.assert_allclose(got, expect, atol=1e-15)
    late = vibration(np.arange(1.0, 4.0, 0.001), np.array([1.0]), np.ones(1), np.zeros(0), V)
    envelope = np.abs(late).reshape(3, -1).max(axis=1)
    assert envelope[0] > envelope[1] > envelope[2]


def test_a_new_hit_overrides_the_vibration_in_progress() -> None:
    hits = np.array([1.0, 1.1])
    t = np.array([1.09, 1.1, 1.15])
    both = vibration(t, hits, np.array([1.0, 0.3]), np.zeros(0), V)
    second = vibration(t, hits[1:], np.array([0.3]), np.zeros(0), V)
    first = vibration(t, hits[:1], np.array([1.0]), np.zeros(0), V)
    assert both[0] == first[0]
    np.testing.assert_array_equal(both[1:], second[1:])  # remaining keys of hit 1 dropped
    assert both[1] == 0.0 and first[1] != 0.0  # the discontinuity the paper accepts


def test_choke_stops_the_cymbal_until_the_next_hit() -> None:
    t = np.array([1.05, 1.25, 1.5, 2.05])
    got = vibration(t, np.array([1.0, 2.0]), np.ones(2), np.array([1.2]), V)
    assert got[0] != 0.0 and got[1] == 0.0 and got[2] == 0.0 and got[3] != 0.0


def test_hihat_top_follows_cc4_and_glow_decays() -> None:
    kit = load_kit("rock5")
    ctl = np.zeros(3, dtype=CONTROL_DTYPE)
    ctl["time_s"] = [0.0, 1.0, 2.0]
    ctl["kind"] = ControlKind.HIHAT_PEDAL
    ctl["number"] = 4
    ctl["value"] = [127, 0, 64]  # closed, open, half
    openness = hihat_openness(np.zeros(0, dtype=ONSET_DTYPE), ctl)
    t = np.array([0.5, 1.5, 2.5])
    np.testing.assert_allclose(openness(t), [0.0, 1.0, 1 - 64 / 127])
    n = len(kit.pieces)
    none = [np.zeros(0)] * n
    ch = kit_channels(kit.pieces, t, none, none, none, [None] * n, openness(t))
    hat = [p.name for p in kit.pieces].index("hihat")
    np.testing.assert_allclose(ch.lift[:, hat], HIHAT_MAX_LIFT_M * openness(t))
    g = glow(np.array([0.9, 1.0, 1.2, 1.5]), np.array([1.0]), np.array([0.8]), 0.15)
    assert g[0] == 0.0 and g[1] == pytest.approx(0.8) and g[1] > g[2] > g[3] > 0


def test_beater_touches_the_kick_head_at_zero_angle() -> None:
    kick = load_kit("rock5").piece("kick")
    contact = zone_target(kick, Zone.HEAD).point
    np.testing.assert_allclose(beater_tip(kick, np.array(0.0)), contact, atol=1e-12)
    back = beater_tip(kick, np.array(0.6))
    assert np.dot(back - contact, kick.normal) == pytest.approx(BEATER_LENGTH_M * np.sin(0.6))


def test_a_first_hit_minutes_into_a_song_overflows_nothing() -> None:
    """A full-band file's drums may start minutes in: the frames before the first hit are
    silent, computed without numpy's overflow warning (which reached the user of `render`)."""
    t = np.arange(0.0, 400.0, 0.5)
    hit = np.array([380.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swing = vibration(t, hit, np.ones(1), np.zeros(0), V)
        lum = glow(t, hit, np.ones(1), 0.001)
    assert np.all(swing[t < 380.0] == 0.0) and np.all(lum[t < 380.0] == 0.0)
    assert np.all(np.isfinite(swing)) and lum[t == 380.0][0] == 1.0
