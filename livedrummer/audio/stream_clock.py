"""Where on the shared clock an output stream's samples are heard, from its FIFO's fill.

A live sound writer keeps an output FIFO (PortAudio's blocking stream) full. Each time it
looks, the samples written so far, ``written``, and those still queued, ``queued``, give an
estimate of when sample 0 of the stream is heard: ``now + (queued - written) / sr +
latency``. The device takes samples from the FIFO a period at a time; the next sample queued
is taken at the next take, not now, so in steady running an estimate is early by the time
left to that take: a sawtooth whose top, the look just before a take, is the truth. A look
can only err early besides: ``now`` is read before the FIFO, so a writer that waits for a
core between the two reads a FIFO the device has drained further. So the clock takes the
*highest* estimate of the last :data:`WINDOW_S` (0.1 s: dozens of looks at every phase of
the period).

Why not a median (the first design, over half a second, plus half a period): JACK's dummy
driver on a loaded machine does not stall and catch up, it slips: a cycle that runs late
moves every later sample late for good (5 slips a second, of 1 to 45 ms, on the shared
2-core machine at load 7). A median follows a slip only when half its window has seen it,
so for a quarter of a second after each one every sound came late by the slip: onsets
placed 18 ms off at p90 (:mod:`services.bench.audio`'s figures before and after are in
docs/benchmarks/sound.md). The highest estimate follows a slip at the next look and within a
tenth of a second one that moves the other way. (``period``, the device's period in samples
where it is known, is kept for the caller's figures; the sawtooth's top needs no correction by
it.)
:meth:`StreamClock.sample_for` turns a show time into the stream's sample index.

Limits: exact to the latency the device reports (for JACK the playback ports' latency,
:mod:`services.display.output_latency`); a sample already written when a slip comes is
heard late by the slip, whatever the clock says (the writer maps each sound to its sample
as late as it can, :mod:`services.display.live_sound`).
"""

from __future__ import annotations

from collections import deque

WINDOW_S = 0.1


class StreamClock:
    """See the module docstring."""

    def __init__(
        self, sr: int, latency_s: float = 0.0, window_s: float = WINDOW_S, period: int = 0
    ) -> None:
        self.sr = sr
        self.latency_s = latency_s
        self.period = period
        self.window_s = window_s
        self._seen: deque[tuple[float, float]] = deque()  # (when, estimate)
        self._zero: float | None = None
        self.looks = 0

    def look(self, now: float, written: int, queued: int) -> None:
        """One look at the FIFO: ``now`` read before ``queued`` (so a look errs only early)."""
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
            self._zero = max(e for _, e in self._seen)
        return self._zero

    def sample_for(self, show_s: float) -> int:
        """The stream's sample heard at shared time ``show_s``."""
        return round((show_s - self.zero_s) * self.sr)
