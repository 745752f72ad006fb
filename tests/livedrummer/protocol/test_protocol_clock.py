"""The shared clock: one timeline across processes; the stepped test clock."""

from __future__ import annotations

import subprocess
import sys
import threading

import pytest

from livedrummer.timeline.clock import MonotonicClock, SteppedClock


def test_monotonic_clock_is_shared_with_another_process() -> None:
    clock = MonotonicClock()
    before = clock.now()
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "from livedrummer.timeline.clock import MonotonicClock; print(repr(MonotonicClock().now()))",
        ],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    after = clock.now()
    child = float(out)
    assert before <= child <= after


def test_monotonic_wait_until_reaches_the_time_or_is_cancelled() -> None:
    clock = MonotonicClock()
    target = clock.now() + 0.01
    assert clock.wait_until(target, threading.Event())
    assert clock.now() >= target
    cancel = threading.Event()
    cancel.set()
    assert not clock.wait_until(clock.now() + 60, cancel)


def test_stepped_clock_moves_only_forward_and_waits_jump() -> None:
    clock = SteppedClock(5.0)
    assert clock.now() == 5.0
    assert clock.advance(0.5) == 5.5
    clock.set(7.0)
    assert clock.wait_until(9.0, threading.Event())
    assert clock.now() == 9.0
    assert clock.wait_until(8.0, threading.Event())
    assert clock.now() == 9.0
    with pytest.raises(ValueError):
        clock.set(1.0)
    with pytest.raises(ValueError):
        clock.advance(-1)
    cancel = threading.Event()
    cancel.set()
    assert not clock.wait_until(20.0, cancel)
    assert clock.now() == 9.0
