"""The output stream's clock: the median of the last half second's estimates, plus half a
period."""

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


def test_stalled_looks_are_ignored_and_a_lasting_shift_followed_within_the_window() -> None:
    clock = StreamClock(SR, window_s=0.5, period=PERIOD)
    steady(clock, 10.0, 500, 10.0)
    before = clock.zero_s
    for i in range(150):  # a third of the looks during stalls: sample 0 "heard" far later
        clock.look(10.49 + i * 1e-5, CAP, CAP)
    assert clock.zero_s == pytest.approx(before, abs=0.2 * PERIOD / SR)
    steady(clock, 10.5, 600, 10.2)  # the device lost 0.2 s for good
    assert clock.zero_s == pytest.approx(10.2, abs=0.1 * PERIOD / SR)
    with pytest.raises(ValueError):
        StreamClock(SR).sample_for(1.0)
