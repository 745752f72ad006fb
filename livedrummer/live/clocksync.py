"""A remote site's clock, and a jitter buffer that keeps its drummer's timing.

Why. A remote drummer's onsets cross a network whose delay varies by tens of milliseconds.
Stamped on arrival (as before), that variation lands in the intervals between hits, and a
groove played evenly there looks ragged here. The sender stamps every hit on its own clock;
if we know that clock's offset (and drift) against ours we can place each hit at its own
time plus one fixed delay, and the intervals survive whatever the network did.

:class:`ClockSync` estimates offset and drift from request/response exchanges in the manner
of NTP: we note our send time ``t0``, the remote answers with its clock ``r`` and we note our
receive time ``t3``; then ``offset = r - (t0 + t3) / 2`` with an error of at most half the
round trip ``t3 - t0``. Exchanges delayed by a queue or a busy machine have long round trips
and uneven halves, so only the exchanges with the shortest round trips in a sliding window
count (minimum-RTT filtering); a least-squares line through them over time gives the drift
once they span :data:`DRIFT_SPAN_S`. The remote time ``r`` is read in one go (the remote's
answer carries one timestamp, taken when it sends), so the remote's own processing time
counts as round trip, which the filter discards as it discards queueing.

:class:`JitterBuffer` chooses the playout delay: each message's transit (arrival here minus
its send time mapped onto our clock) is kept for ``window_s``; the delay is a high quantile
of those transits plus a margin. It rises at once when the network gets worse, that is when a
message arrives within half the margin of the delay (a hit played late is worse than one
interval stretched once), but not while the quantile merely creeps up and every message is
still in time (each rise stretches an interval); it falls slowly, at ``fall_rate`` seconds
per second, when the network gets better, so intervals shrink by at most that fraction while
it adapts. A hit whose playout time has already passed when it arrives is played at once and
counted as late.

Limits: the offset is only as good as the path is symmetric (an asymmetric route biases it by
half the asymmetry, as for NTP); drift is assumed constant over the window; the delay covers
the network's jitter at the chosen quantile, so with a 0.99 quantile about one hit in a
hundred may still come late after a sudden change.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

DRIFT_SPAN_S = 20.0  # fit a drift only over samples spanning at least this long


@dataclass(frozen=True)
class SyncSample:
    """One exchange: our send time, the remote's clock in its answer, our receive time."""

    sent_s: float
    remote_s: float
    received_s: float

    @property
    def rtt_s(self) -> float:
        return self.received_s - self.sent_s

    @property
    def offset_s(self) -> float:
        """Remote clock minus ours, assuming the two halves of the trip took as long."""
        return self.remote_s - (self.sent_s + self.received_s) / 2


class ClockSync:
    """Offset and drift of a remote clock (see the module docstring).

    The offset comes from the ``best`` shortest round trips among the last ``window``
    exchanges; the drift from a longer history: the shortest round trip of every ``block``
    exchanges is kept as an anchor (up to ``anchors`` of them), and a line is fitted through
    the better half of the anchors once they span :data:`DRIFT_SPAN_S`.
    """

    def __init__(
        self, window: int = 128, best: int = 8, block: int = 8, anchors: int = 128
    ) -> None:
        if best < 1 or window < best or block < 1:
            raise ValueError("need 1 <= best <= window and block >= 1")
        self.best, self.block = best, block
        self.samples: deque[SyncSample] = deque(maxlen=window)
        self.anchors: deque[SyncSample] = deque(maxlen=anchors)
        self._pending: list[SyncSample] = []
        self._fit: tuple[float, float, float] | None = None  # (t_ref, offset at t_ref, drift)

    def add(self, sample: SyncSample) -> None:
        """One more exchange; a negative round trip (a clock stepped) is ignored."""
        if sample.rtt_s < 0:
            return
        self.samples.append(sample)
        self._pending.append(sample)
        if len(self._pending) >= self.block:
            self.anchors.append(min(self._pending, key=lambda x: x.rtt_s))
            self._pending.clear()
        self._fit = None

    @property
    def ready(self) -> bool:
        return len(self.samples) > 0

    @property
    def uncertainty_s(self) -> float:
        """Half the shortest round trip: the most the offset can be off on a symmetric path."""
        return min(s.rtt_s for s in self.samples) / 2 if self.samples else float("inf")

    def _drift(self) -> float:
        if len(self.anchors) < 6:
            return 0.0
        cut = float(np.median([a.rtt_s for a in self.anchors]))
        good = [a for a in self.anchors if a.rtt_s <= cut]
        t = np.array([(a.sent_s + a.received_s) / 2 for a in good])
        if len(good) < 3 or t.max() - t.min() < DRIFT_SPAN_S:
            return 0.0
        off = np.array([a.offset_s for a in good])
        return float(np.polyfit(t - t.mean(), off, 1)[0])

    def _chosen(self) -> tuple[float, float, float]:
        if self._fit is None:
            if not self.samples:
                raise ValueError("no exchanges yet")
            drift = self._drift()
            ordered = sorted(self.samples, key=lambda s: s.rtt_s)[: self.best]
            t = np.array([(s.sent_s + s.received_s) / 2 for s in ordered])
            off = np.array([s.offset_s for s in ordered])
            t_ref = float(t.mean())
            # each offset carried to t_ref along the drift, then averaged
            self._fit = (t_ref, float(np.mean(off - drift * (t - t_ref))), drift)
        return self._fit

    @property
    def drift(self) -> float:
        """Seconds the remote clock gains per second of ours (0 until the anchors span
        :data:`DRIFT_SPAN_S`)."""
        return self._chosen()[2]

    def offset_at(self, local_s: float) -> float:
        """Remote minus local clock at our time ``local_s``."""
        t_ref, offset, drift = self._chosen()
        return offset + drift * (local_s - t_ref)

    def to_local(self, remote_s: float) -> float:
        """Our clock's reading when the remote clock read ``remote_s``."""
        t_ref, offset, drift = self._chosen()
        # remote = local + offset + drift * (local - t_ref)  =>  solve for local
        return (remote_s - offset + drift * t_ref) / (1.0 + drift)


class JitterBuffer:
    """Playout delay from observed transits (see the module docstring)."""

    def __init__(
        self,
        quantile: float = 0.99,
        window_s: float = 10.0,
        margin_s: float = 0.003,
        fall_rate: float = 0.002,
        max_delay_s: float = 1.0,
    ) -> None:
        if not 0.5 <= quantile <= 1.0:
            raise ValueError("quantile must be within 0.5..1")
        self.quantile, self.window_s, self.margin_s = quantile, window_s, margin_s
        self.fall_rate, self.max_delay_s = fall_rate, max_delay_s
        self.transits: deque[tuple[float, float]] = deque()
        self.delay_s: float | None = None
        self.late = 0
        self._last_s: float | None = None

    def observe(self, transit_s: float, now_s: float) -> float:
        """One message's transit; returns the delay now in force."""
        self.transits.append((now_s, transit_s))
        while self.transits and self.transits[0][0] < now_s - self.window_s:
            self.transits.popleft()
        values = np.fromiter((t for _, t in self.transits), float, len(self.transits))
        target = min(float(np.quantile(values, self.quantile)) + self.margin_s, self.max_delay_s)
        if self.delay_s is None:
            self.delay_s = target
        elif target > self.delay_s and transit_s > self.delay_s - self.margin_s / 2:
            # a message came (nearly) too late: the network got worse, follow it now; a
            # quantile that only creeps up while every message still arrives in time moves
            # nothing, since each rise stretches one interval between two hits
            self.delay_s = target
        elif target < self.delay_s and self._last_s is not None:
            fall = self.fall_rate * max(0.0, now_s - self._last_s)
            self.delay_s = max(target, self.delay_s - fall)
        self._last_s = now_s
        return self.delay_s

    def playout(self, sent_local_s: float, now_s: float) -> float:
        """When an event sent at ``sent_local_s`` (our clock) is played: its send time plus
        the delay, or now if that has passed (counted in ``late``)."""
        delay = self.delay_s if self.delay_s is not None else 0.0
        due = sent_local_s + delay
        if due < now_s:
            self.late += 1
            return now_s
        return due
