"""One clock for every livedrummer process on a machine, injected where time is read.

Why this clock. Onsets are stamped by the input daemon, poses by the synth and frames by the
display, each in its own process; their times are only comparable on a clock all of them read
alike. On Linux ``time.monotonic_ns`` is ``CLOCK_MONOTONIC``: one system-wide counter, never
stepped by NTP or the user, so two processes reading it at the same instant get the same value
(macOS's ``mach_absolute_time`` and Windows' ``QueryPerformanceCounter`` are system-wide too).
Wall time (``time.time``) is never used for ordering; it may jump.

Why injected. Code that needs "now" or "wait until" takes a :class:`Clock`; production passes
:class:`MonotonicClock`, tests pass :class:`SteppedClock`, whose ``wait_until`` jumps to the
deadline at once, so a 30-second MIDI file "plays in real time" in microseconds, deterministically.

Limits: the clock is per machine. Times from another machine (a remote jam) are on *its*
clock: a remote source that can reach the other site's control socket maps them onto ours
with an estimated offset and drift (:mod:`livedrummer.live.clocksync`); one that cannot
restamps them on arrival.
"""

from __future__ import annotations

import threading
import time
from typing import Protocol


class Clock(Protocol):
    """Seconds on the machine's shared monotonic timeline."""

    def now(self) -> float: ...

    def wait_until(self, time_s: float, cancel: threading.Event) -> bool:
        """Block until ``time_s`` or until ``cancel`` is set; True if the time was reached."""
        ...


class MonotonicClock:
    """Production clock: ``CLOCK_MONOTONIC`` in float seconds (shared by all processes)."""

    def now(self) -> float:
        return time.monotonic_ns() * 1e-9

    def wait_until(self, time_s: float, cancel: threading.Event) -> bool:
        while True:
            left = time_s - self.now()
            if left <= 0:
                return True
            if cancel.wait(left):
                return False


class SteppedClock:
    """Test clock: time moves only when the test (or a wait) moves it."""

    def __init__(self, start_s: float = 0.0) -> None:
        self._now = start_s
        self._lock = threading.Lock()

    def now(self) -> float:
        with self._lock:
            return self._now

    def advance(self, dt_s: float) -> float:
        if dt_s < 0:
            raise ValueError(f"a clock cannot go back (advance by {dt_s})")
        with self._lock:
            self._now += dt_s
            return self._now

    def set(self, time_s: float) -> None:
        with self._lock:
            if time_s < self._now:
                raise ValueError(f"a clock cannot go back ({time_s} < {self._now})")
            self._now = time_s

    def wait_until(self, time_s: float, cancel: threading.Event) -> bool:
        if cancel.is_set():
            return False
        with self._lock:
            self._now = max(self._now, time_s)
        return True
