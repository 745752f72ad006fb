"""Bad network messages: dropped, counted per kind, logged once per kind.

Why one helper. Every socket that decodes what a peer sent (the synth's event SUB and control
ROUTER, the display's pose SUB, the input daemon's control ROUTER, the remote source's SUB)
must treat bad bytes the same way: never crash, never stall, never lose them silently. A
:class:`BadMessages` sits next to each such socket. ``drop(exc)`` turns the
:class:`~livedrummer.errors.ProtocolError` that :func:`~livedrummer.protocol.decode` raised
into a short *kind* (:func:`kind_of`), counts it, and logs a warning the first time that kind
is seen on that socket (then it only counts, so a peer spraying garbage cannot flood the log).
``summary()`` gives the counts for a service's status and on-exit log line.

Kinds (:func:`kind_of`, kept with the intake in :mod:`livedrummer.protocol.intake`), from the
``field`` a :class:`~livedrummer.protocol.WireError` names:

    version    the header's version byte is not ours
    header     header frame of the wrong size (truncated, random bytes), bad magic, unknown
               kind, or header values out of range (flags, performer, stream, seq, send time)
    oversized  payload_len above the receiver's limit (``max_payload``)
    size       payload_len disagrees with the bytes in the payload frames
    frames     no frames, or the wrong number of frames for the kind (multi-frame garbage)
    payload    the payload itself is invalid (rows out of range, bad HELLO JSON, pose hash)
    unexpected a valid message of a kind this socket does not serve (``unexpected``)

Limits. What ZeroMQ drops before we see it is not counted here: a SUB socket subscribed to
the protocol magic never receives frames that do not start with ``LDRM`` (those cannot come
from a livedrummer sender), and a frame above ``MAX_FRAME`` (see :mod:`services.wire.net`) makes
ZeroMQ close that connection (the peer reconnects; the loss shows as a sequence gap).
"""

from __future__ import annotations

import logging
import threading
from collections import Counter

from livedrummer.errors import ProtocolError
from livedrummer.protocol.intake import KINDS, kind_of

__all__ = ["KINDS", "BadMessages", "kind_of"]


class BadMessages:
    """Counts dropped messages of one socket by kind; logs each kind once. Thread-safe."""

    def __init__(self, where: str, logger: logging.Logger) -> None:
        self.where = where
        self._log = logger
        self._lock = threading.Lock()
        self.counts: Counter[str] = Counter()

    def drop(self, exc: ProtocolError) -> str:
        """Count a message that failed to decode; return its kind."""
        kind = kind_of(exc)
        self._count(kind, str(exc))
        return kind

    def unexpected(self, what: str) -> None:
        """Count a valid message this socket does not serve (``what`` names it)."""
        self._count("unexpected", f"{what} is not served here")

    def count(self, kind: str, detail: str) -> None:
        """Count a dropped message of another protocol (OSC) by its own ``kind``."""
        self._count(kind, detail)

    def _count(self, kind: str, detail: str) -> None:
        with self._lock:
            first = kind not in self.counts
            self.counts[kind] += 1
        if first:
            self._log.warning(
                "%s: dropped a bad message (%s): %s; further ones of this kind are counted, "
                "not logged",
                self.where,
                kind,
                detail,
            )

    @property
    def total(self) -> int:
        with self._lock:
            return sum(self.counts.values())

    def summary(self) -> dict[str, int]:
        """Counts by kind (only kinds seen), for status and on-exit log lines."""
        with self._lock:
            return {k: self.counts[k] for k in sorted(self.counts)}

    def log_summary(self) -> None:
        """One warning line with the totals (at exit); nothing when no message was dropped."""
        counts = self.summary()
        if counts:
            self._log.warning("%s: dropped bad messages: %s", self.where, counts)
