"""Where on the shared clock an output stream's samples are heard, from its FIFO's fill.

A live sound writer keeps an output FIFO (PortAudio's blocking stream) full. Each time it
looks, the samples written so far, ``written``, and those still queued, ``queued``, give an
estimate of when sample 0 of the stream is heard: ``now + (queued - written) / sr +
latency``. The device takes samples from the FIFO a period at a time; the next sample queued
is taken at the next take, not now, so in steady running an estimate is early by the time
left to that take: spread evenly over one period below the truth. A look at a stalled or
catching-up device (JACK's dummy driver on a loaded machine) is an outlier either side, and
on a loaded machine there are many. The clock takes the median of the estimates of the last
:data:`WINDOW_S` plus half the device's period (``period`` samples, where it is known: JACK's
buffer size): right in steady running, deaf to outliers up to nearly half the looks, and
following a lasting change (a device clock that drifts from ours) within half the window.
(The 90th percentile, tried first, was a tenth of a period early in steady running but 5 ms
early on a machine at load 8, where stalled looks were over a tenth.)
:meth:`StreamClock.sample_for` turns a show time into the stream's sample index.

Limits: exact to the latency the device reports (for JACK the playback ports' latency,
:mod:`services.display.output_latency`); without a known period (ALSA) half a period early.
"""

from __future__ import annotations

from collections import deque

import numpy as np

WINDOW_S = 0.5


class StreamClock:
    """See the module docstring."""

    def __init__(self, sr: int, latency_s: float = 0.0, window_s: float = WINDOW_S,
                 period: int = 0) -> None:  # fmt: skip
        self.sr = sr
        self.latency_s = latency_s
        self.period = period
        self.window_s = window_s
        self._seen: deque[tuple[float, float]] = deque()  # (when, estimate)
        self._zero: float | None = None
        self.looks = 0

    def look(self, now: float, written: int, queued: int) -> None:
        """One look at the FIFO at shared time ``now``."""
        self._seen.append((now, now + (queued - written) / self.sr + self.latency_s))
        while self._seen[0][0] < now - self.window_s:
            self._seen.popleft()
        self._zero = None
        self.looks += 1

    @property
    def zero_s(self) -> float:
        """Shared time at which sample 0 of the stream is heard."""
        if not self._seen:
            raise ValueError("no look at the stream yet")
        if self._zero is None:
            median = float(np.median([e for _, e in self._seen]))
            self._zero = median + 0.5 * self.period / self.sr
        return self._zero

    def sample_for(self, show_s: float) -> int:
        """The stream's sample heard at shared time ``show_s``."""
        return round((show_s - self.zero_s) * self.sr)
