"""Where on the shared clock an output stream's samples are heard, from its FIFO's fill.

A live sound writer keeps an output FIFO (PortAudio's blocking stream) full. Each time it
looks, the samples written so far, ``written``, and those still queued, ``queued``, give an
estimate of when sample 0 of the stream is heard: ``now + (queued - written) / sr +
latency``. The device takes samples from the FIFO a period at a time; the next sample queued
is taken at the next take, not now, so in steady running an estimate is early by the time
left to that take: spread evenly over one period below the truth. A look at a stalled or
catching-up device (JACK's dummy driver on a loaded machine) is an outlier either side. The
clock takes the :data:`QUANTILE` (90th percentile) of the estimates of the last
:data:`WINDOW_S`: a tenth of a period early in steady running, deaf to the odd outlier, and
following a lasting change (a device clock that drifts from ours) within the window.
:meth:`StreamClock.sample_for` turns a show time into the stream's sample index.

Limits: exact to the latency the device reports (for JACK the playback ports' latency,
:mod:`services.display.output_latency`) and to a tenth of a period; a change that lasts less
than a tenth of the window is ignored, one that lasts longer is followed within the window.
"""

from __future__ import annotations

from collections import deque

import numpy as np

WINDOW_S = 0.5
QUANTILE = 90.0


class StreamClock:
    """See the module docstring."""

    def __init__(self, sr: int, latency_s: float = 0.0, window_s: float = WINDOW_S) -> None:
        self.sr = sr
        self.latency_s = latency_s
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
            self._zero = float(np.percentile([e for _, e in self._seen], QUANTILE))
        return self._zero

    def sample_for(self, show_s: float) -> int:
        """The stream's sample heard at shared time ``show_s``."""
        return round((show_s - self.zero_s) * self.sr)
