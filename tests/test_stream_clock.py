"""The output stream's clock: a high quantile of the last half second's estimates."""

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


def test_in_steady_running_it_is_a_tenth_of_a_period_early_at_most() -> None:
    clock = StreamClock(SR, latency_s=0.002)
    steady(clock, 1.0, 600, 1.0)
    true = 1.0 + 0.002
    assert true - 0.15 * PERIOD / SR <= clock.zero_s <= true
    assert abs(clock.sample_for(1.5 + 0.002) - 24_000) <= 0.15 * PERIOD


def test_an_odd_stall_is_ignored_and_a_lasting_shift_followed_within_the_window() -> None:
    clock = StreamClock(SR, window_s=0.5)
    steady(clock, 10.0, 500, 10.0)
    before = clock.zero_s
    clock.look(10.49, CAP, CAP)  # one look during a stall: sample 0 "heard" at 10.49
    assert clock.zero_s == pytest.approx(before, abs=1e-5)
    steady(clock, 10.5, 600, 10.2)  # the device lost 0.2 s for good
    assert clock.zero_s == pytest.approx(10.2, abs=0.15 * PERIOD / SR)
    with pytest.raises(ValueError):
        StreamClock(SR).sample_for(1.0)
