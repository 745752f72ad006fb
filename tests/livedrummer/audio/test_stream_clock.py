"""The output stream's clock: the highest of the last tenth of a second's estimates."""

from __future__ import annotations

import pytest

from livedrummer.audio.stream_clock import StreamClock

SR = 48_000
PERIOD, CAP = 128, 512


def steady(clock: StreamClock, start: float, looks: int, zero: float) -> None:
    """Looks at many phases of the period at a device whose sample 0 is heard at ``zero``:
    it takes PERIOD samples at zero + k * PERIOD / SR; the writer keeps the FIFO full."""
    for i in range(looks):
        now = start + i * 0.00097  # a look about every millisecond
        taken = (int((now - zero) * SR) // PERIOD + 1) * PERIOD
        clock.look(now, taken + CAP, CAP)


def test_in_steady_running_it_is_right_to_a_tenth_of_a_period() -> None:
    clock = StreamClock(SR, latency_s=0.002, period=PERIOD)
    steady(clock, 1.0, 600, 1.0)
    assert clock.zero_s == pytest.approx(1.0 + 0.002, abs=0.1 * PERIOD / SR)
    assert abs(clock.sample_for(1.5 + 0.002) - 24_000) <= 0.1 * PERIOD


def test_early_looks_are_ignored_and_a_slip_is_followed_at_once_and_back_within_the_window() -> (
    None
):
    clock = StreamClock(SR, period=PERIOD)
    steady(clock, 10.0, 200, 10.0)
    before = clock.zero_s
    for i in range(60):  # the writer waited for a core between reading the time and the FIFO
        now = 10.195 + i * 1e-5  # (which the device had drained by three more periods)
        taken = (int((now - 10.0) * SR) // PERIOD + 1) * PERIOD
        clock.look(now, taken + CAP, CAP - 3 * PERIOD)
    assert clock.zero_s == pytest.approx(before, abs=0.1 * PERIOD / SR)
    steady(clock, 10.2, 3, 10.015)  # the dummy driver slipped 15 ms, for good: three looks on
    # (a period's phases, a look a millisecond) it is right to the spacing of the looks
    assert clock.zero_s == pytest.approx(10.015, abs=0.001)
    steady(clock, 10.21, 120, 10.008)  # a device that catches 7 ms up: within the window
    assert clock.zero_s == pytest.approx(10.008, abs=0.1 * PERIOD / SR)
    with pytest.raises(ValueError):
        StreamClock(SR).sample_for(1.0)
