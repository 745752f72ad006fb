"""The live twin of the ensemble warp: a seeded, bounded, smooth shift and gain per onset."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.stage.variation import (
    Variation,
    bounded,
    live_gain,
    live_shift,
    vary_live,
)
from livedrummer.timeline.events import ONSET_DTYPE

TIMES = np.linspace(0.0, 60.0, 3001)


def test_shift_is_never_negative_and_within_the_bound() -> None:
    v = bounded(Variation(warp_s=0.05, seed=7), delay_s=0.06, lookahead_s=0.03)
    assert v.warp_s == pytest.approx(0.03)
    s = live_shift(TIMES, v)
    assert s.min() >= 0.0 and s.max() <= 0.03
    assert s.max() > 0.02 and s.min() < 0.01  # it wanders over its range


def test_shift_is_seeded_smooth_and_order_keeping() -> None:
    a = live_shift(TIMES, Variation(warp_s=0.03, seed=1))
    np.testing.assert_array_equal(a, live_shift(TIMES, Variation(warp_s=0.03, seed=1)))
    # stateless: asked out of order or one by one, the same shift (bit-exact by design: each
    # time's shift is computed from that time alone, element by element, on this machine)
    rev = live_shift(TIMES[::-1], Variation(warp_s=0.03, seed=1))[::-1]
    np.testing.assert_array_equal(a, rev)
    assert float(live_shift(TIMES[1234:1235], Variation(warp_s=0.03, seed=1))[0]) == a[1234]
    step = np.abs(np.diff(a))
    assert step.max() < 0.03 * 0.02 * 1.5 / 2.0 + 1e-9  # slope <= 1.5·W/knot over 20 ms
    shifted = TIMES + a
    assert np.all(np.diff(shifted) > 0)


def test_copies_differ() -> None:
    shifts = [live_shift(TIMES, Variation(warp_s=0.03, seed=k)) for k in range(3)]
    for i in range(3):
        for j in range(i + 1, 3):
            assert np.abs(shifts[i] - shifts[j]).max() > 0.005


def test_gain_within_r_and_velocity_scaled() -> None:
    v = Variation(warp_s=0.02, amplitude=0.2, seed=3)
    g = live_gain(TIMES, v)
    assert g.min() >= 0.8 - 1e-12 and g.max() <= 1.2 + 1e-12
    assert g.max() - g.min() > 0.15
    rows = np.zeros(TIMES.size, ONSET_DTYPE)
    rows["time_s"] = TIMES
    rows["velocity"] = 100
    out = vary_live(rows, v)
    assert out["velocity"].min() >= 80 and out["velocity"].max() <= 120
    assert len(set(out["velocity"].tolist())) > 5
    d = out["time_s"] - rows["time_s"]
    assert d.min() >= 0 and d.max() <= 0.02 + 1e-6
    np.testing.assert_array_equal(out["note"], rows["note"])


def test_no_variation_is_identity() -> None:
    rows = np.zeros(5, ONSET_DTYPE)
    rows["time_s"] = np.arange(5.0)
    rows["velocity"] = 90
    out = vary_live(rows, Variation(warp_s=0.0, amplitude=0.0))
    np.testing.assert_array_equal(out, rows)
