"""The calibration estimate (pure logic): matching hits to clicks, median lag, outliers."""

import numpy as np
import pytest

from livedrummer.live.calibrate import click_times, estimate


def test_the_median_lag_survives_flams_and_stray_hits() -> None:
    clicks = click_times(10.0, 120.0, 16)
    rng = np.random.default_rng(3)
    hits = clicks + 0.023 + rng.normal(0, 0.004, clicks.size)
    extra = [clicks[3] + 0.040, clicks[7] + 0.25]  # a flam, a stray hit between clicks
    got = estimate(clicks, np.concatenate([hits, extra]))
    assert abs(got.median_ms - 23.0) < 2.5 and got.used == 16 and got.dropped == 2
    assert 1.0 < got.spread_ms < 5.0


def test_too_few_hits_say_so() -> None:
    with pytest.raises(ValueError, match="need at least 4"):
        estimate(click_times(0.0, 100.0, 8), np.array([0.01, 0.61]))
