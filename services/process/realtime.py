"""Real-time scheduling for a latency-critical process (the input daemon on a stage rig).

On a busy machine a note can wait for the CPU behind the synthesizer's re-animation or the
display's drawing. ``SCHED_FIFO`` at a modest priority (JACK itself uses 70 and above for its
audio threads; we stay below) lets the daemon run as soon as a message arrives. Linux sets
the policy per thread and new threads inherit it, so :func:`request_realtime` is called
before any thread starts (ZeroMQ's I/O threads, the MIDI callback thread). The daemon only
ever blocks on I/O, so a FIFO priority cannot starve the machine through busy waiting.

Without the privilege (no root, no ``LimitRTPRIO``/rtprio limit; see
``deploy/systemd/livedrummer-input.service``) the request is refused: that is logged once
and the process runs with the normal policy, never fails.
"""

from __future__ import annotations

import logging
import os

log = logging.getLogger(__name__)

MAX_PRIORITY = 60  # below JACK's audio threads


def request_realtime(priority: int, what: str) -> bool:
    """Ask for ``SCHED_FIFO`` at ``priority`` (1..60) for this thread and the threads it
    starts later; False (and one warning) if the system refuses."""
    if not 1 <= priority <= MAX_PRIORITY:
        raise ValueError(f"real-time priority {priority}: expected 1..{MAX_PRIORITY}")
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except (PermissionError, OSError) as exc:
        log.warning(
            "%s: no real-time scheduling (%s); running at normal priority",
            what,
            exc.strerror or exc,
        )
        return False
    log.info("%s: SCHED_FIFO priority %d", what, priority)
    return True
