"""The live display's estimate of its own latency (livedrummer.live.ahead)."""

from __future__ import annotations

import pytest

from livedrummer.live.ahead import RenderAhead


def test_starts_at_zero_and_follows_the_slow_frames() -> None:
    ahead = RenderAhead(window=10, quantile=0.9)
    assert ahead.seconds == 0.0
    for k in range(10):
        ahead.add(0.004 if k % 5 else 0.012)  # two slow frames in ten
    assert 0.004 < ahead.seconds <= 0.012
    for _ in range(10):  # the load went away: the window forgets the slow ones
        ahead.add(0.003)
    assert ahead.seconds == pytest.approx(0.003)


def test_a_stalled_frame_is_capped_and_bad_settings_refused() -> None:
    ahead = RenderAhead(window=3, quantile=1.0, limit_s=0.1)
    ahead.add(5.0)
    assert ahead.seconds == pytest.approx(0.1)
    ahead.add(-1.0)  # a clock step cannot make it negative
    assert ahead.seconds == pytest.approx(0.1)
    with pytest.raises(ValueError, match="quantile"):
        RenderAhead(quantile=0.0)
