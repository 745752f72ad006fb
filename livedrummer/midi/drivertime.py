"""Driver timestamps onto the shared clock: a MIDI driver's delta times, anchored once.

Why this shape. A note's time must be when the driver saw it, not when Python got round to it:
on a loaded machine the input daemon's thread may wait milliseconds for the CPU (and, with an
rtmidi callback, for the interpreter lock inside the driver's own thread). python-rtmidi, read
by polling its queue, gives each message the time since the previous one, measured in the
driver's thread: JACK's ``jack_get_time()`` in the process callback, the ALSA sequencer's
real-time event stamp. Their running sum is the driver's timeline, exact up to an unknown
constant; this module estimates that constant and adds it.

The estimate. Every message is read at some time ``r`` on the shared clock no earlier than it
arrived, so ``r - sum`` is an upper bound of the constant, and the smallest bound seen so far
is the best: it comes from the message that was read soonest (the first of a burst after a
quiet moment, read within one poll interval). So a stamp is never later than its read and
never earlier than the driver's own time; a late read (the daemon starved) no longer moves
it. The bound may age upwards by :data:`DRIFT` (10 ppm) of the time since it was last
tightened, so a driver clock slightly slower than ours is followed rather than left behind
(the JACK and ALSA clocks used here are the system's monotonic clock, so in practice the
anchor never moves).

Limits. The first message after a (re)open anchors the timeline on its read: until a message
is read promptly, stamps can be late by that first read's delay. A stamp that would sit more
than :data:`MAX_LAG_S` before its read means the driver's timeline was broken (a new client,
deltas lost): the anchor restarts on that read and :attr:`DeltaStamper.resyncs` counts it.
Deltas of messages the driver itself discards are lost (rtmidi's JACK backend measures the
delta before applying its ignore filter), which is why the caller must not let the driver
filter anything and drops unwanted messages itself.
"""

from __future__ import annotations

import math

#: How fast the anchor may age upwards: seconds per second since it was last tightened.
DRIFT = 1e-5
#: Beyond this lag between a stamp and its read, the driver's timeline is taken as broken.
MAX_LAG_S = 2.0


class DeltaStamper:
    """Online: ``stamp(delta_s, read_s)`` per message, in driver order; ``reset()`` on reopen."""

    def __init__(self) -> None:
        self.resyncs = 0
        self.reset()

    def reset(self) -> None:
        """Forget the timeline (a new driver client starts its deltas from zero)."""
        self._sum = 0.0
        self._anchor = math.inf  # the smallest read - sum seen (with ageing)
        self._tightened = 0.0  # read time when the anchor was last set

    def stamp(self, delta_s: float, read_s: float) -> float:
        """The shared-clock time of a message ``delta_s`` after the previous one, read at
        ``read_s``. Never later than ``read_s``; never earlier than an earlier stamp."""
        self._sum += max(delta_s, 0.0)
        bound = read_s - self._sum
        aged = self._anchor + DRIFT * max(read_s - self._tightened, 0.0)
        if bound <= aged:
            self._anchor, self._tightened = bound, read_s
        else:
            self._anchor, self._tightened = aged, read_s
        t = self._sum + self._anchor
        if read_s - t > MAX_LAG_S:
            self.resyncs += 1
            self._anchor, self._tightened = bound, read_s
            t = read_s
        return t
