"""The one stream receiver: a SUB socket drained without blocking, through one intake.

Why one. The synth (reading an input daemon), the live and the stage display (reading a
synth), the practice rig's onset bus and a remote jam's source (reading an input daemon) and
the display's sound process (reading a synth's forwarded onsets) all subscribe to a numbered
livedrummer stream. Each used to read its socket, decode, filter, observe the sequence
numbers and count bad messages itself, and their sequence-number policies had drifted (one
display ignored a restarted synth that another reset for). :class:`StreamReceiver` is that
loop once: the pure steps are :class:`~livedrummer.protocol.StreamIntake`'s (decode, kind,
performer, the sequence policy of :mod:`livedrummer.protocol.sequence`); this module owns the
socket and the log. The practice readout's JSON stream is not numbered, but it drains its
socket with :func:`waiting` too, so no other module reads a SUB socket (a test pins it).

Drain. :meth:`StreamReceiver.drain` reads what is waiting, without blocking, up to a budget
of messages (:data:`DRAIN_BUDGET`), so a flood cannot hold a caller's loop (a display's
frame, the synth's answer) for longer than the budget's worth of decoding; the caller drains
again on its next turn. It returns a :class:`Batch`: the messages taken, each with its
sequence report (a GAP's count, a RESTART), and what the drain read and dropped.

Log. A bad message is counted per kind and logged the first time its kind is seen
(:class:`~services.wire.badmsg.BadMessages`; totals at :meth:`close`). Lost, duplicate and restart
events are logged in one line each at most every :data:`LOG_EVERY_S`: the first at once, the
rest summed into the next line, so a lossy link cannot flood the log; :meth:`close` writes
what is still unsaid. Nothing a peer sends raises out of :meth:`drain`.

Limits: one socket per receiver, read from one thread (the caller's); messages a ZeroMQ
subscription filters out (no magic, or kinds not subscribed) are never seen, so a receiver
that subscribes to some kinds only must be built with ``sequenced=False``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import zmq

from livedrummer.protocol import (
    MAX_PAYLOAD,
    Dropped,
    Kind,
    Message,
    PoseFormat,
    SeqStatus,
    StreamIntake,
    Taken,
)

from .badmsg import BadMessages
from .net import DEFAULT_HWM, Security, connect, socket, subscribe_protocol

DRAIN_BUDGET = 1000  # messages read by one drain, at most
LOG_EVERY_S = 10.0  # at most one loss/restart line this often


def waiting(sock: Any, budget: int, multipart: bool = True) -> list[Any]:
    """Up to ``budget`` messages queued on ``sock`` (frame lists, or single frames with
    ``multipart=False``), read without blocking: the one place a SUB socket is read."""
    out: list[Any] = []
    read = sock.recv_multipart if multipart else sock.recv
    for _ in range(budget):
        try:
            out.append(read(zmq.NOBLOCK))
        except zmq.Again:
            break
    return out


@dataclass
class Batch:
    """What one drain read: the messages taken (in arrival order) and the counts."""

    taken: list[Taken] = field(default_factory=list)
    read: int = 0  # messages read off the socket, taken or not
    bad: int = 0
    duplicates: int = 0
    missing: int = 0
    restarts: int = 0

    @property
    def messages(self) -> list[Message]:
        return [t.msg for t in self.taken]


@dataclass(frozen=True)
class Counts:
    """A receiver's totals: the same numbers whichever service owns it."""

    received: int
    missing: int
    duplicates: int
    restarts: int
    bad: int


class _SeqLog:
    """Loss, duplicate and restart lines, one at most every LOG_EVERY_S (module docstring)."""

    def __init__(self, where: str, log: logging.Logger, clock: Callable[[], float]) -> None:
        self.where, self._log, self._clock = where, log, clock
        self._next_s = -math.inf
        self._missing = self._gaps = self._restarts = self._duplicates = 0
        self._last_seq = 0

    def note(self, status: SeqStatus | None, seq: int, missing: int = 0) -> None:
        if status is SeqStatus.GAP:
            self._missing += missing
            self._gaps += 1
        elif status is SeqStatus.RESTART:
            self._restarts += 1
        elif status is None:
            self._duplicates += 1
        else:
            return
        self._last_seq = seq
        now = self._clock()
        if now >= self._next_s:
            self.flush()
            self._next_s = now + LOG_EVERY_S

    def flush(self) -> None:
        parts = []
        if self._gaps:
            gaps = "" if self._gaps == 1 else f" in {self._gaps} gaps"
            parts.append(f"{self._missing} messages lost{gaps}")
        if self._restarts:
            times = "" if self._restarts == 1 else f" {self._restarts} times"
            parts.append(f"the sender restarted{times} (its numbers began again)")
        if self._duplicates:
            parts.append(f"{self._duplicates} duplicate or reordered messages dropped")
        if parts:
            self._log.warning("%s: %s, up to #%d", self.where, "; ".join(parts), self._last_seq)
        self._missing = self._gaps = self._restarts = self._duplicates = 0


class StreamReceiver:
    """A SUB socket on one numbered stream; see the module docstring.

    ``where`` names the stream in log lines ("synth input stream"); ``kinds``, ``pose_format``,
    ``performer`` and ``sequenced`` are the intake's (:class:`~livedrummer.protocol.StreamIntake`).
    ``clock`` times the loss lines only. Nothing is opened until :meth:`connect`.
    """

    def __init__(
        self,
        where: str,
        log: logging.Logger,
        kinds: Iterable[Kind],
        pose_format: PoseFormat | None = None,
        performer: int | None = None,
        sequenced: bool = True,
        max_payload: int = MAX_PAYLOAD,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.where = where
        self.intake = StreamIntake(kinds, pose_format, performer, sequenced, max_payload)
        self.bad = BadMessages(where, log)
        self.sock: Any = None
        self._seqlog = _SeqLog(where, log, clock)

    @property
    def tracker(self) -> Any:
        """The intake's :class:`~livedrummer.protocol.SequenceTracker` (per-stream counts)."""
        return self.intake.tracker

    def connect(
        self,
        ctx: zmq.Context[zmq.Socket[bytes]],
        endpoint: str,
        what: str,
        security: Security | None = None,
        topics: Iterable[bytes] | None = None,
        hwm: int = DEFAULT_HWM,
    ) -> None:
        """Open the SUB socket, subscribe (every livedrummer message, or ``topics``) and
        connect; a bad endpoint or key raises the named error of :func:`services.wire.net.connect`
        with the socket closed."""
        sock = socket(ctx, zmq.SUB, hwm)
        try:
            if topics is None:
                subscribe_protocol(sock)
            else:
                for t in topics:
                    sock.setsockopt(zmq.SUBSCRIBE, t)
            connect(sock, endpoint, what, security)
        except BaseException:
            sock.close(0)
            raise
        self.sock = sock

    def poll(self, timeout_ms: int) -> bool:
        """True when a message is waiting (within ``timeout_ms``)."""
        return bool(self.sock.poll(timeout_ms))

    def drain(self, budget: int = DRAIN_BUDGET) -> Batch:
        """Read and take up to ``budget`` waiting messages (see the module docstring)."""
        batch = Batch()
        for frames in waiting(self.sock, budget):
            batch.read += 1
            got = self.take(frames)
            if isinstance(got, Taken):
                batch.taken.append(got)
                batch.missing += got.seq.missing
                batch.restarts += got.seq.status is SeqStatus.RESTART
            elif got.kind == "duplicate":
                batch.duplicates += 1
            else:
                batch.bad += 1
        return batch

    def take(self, frames: list[bytes]) -> Taken | Dropped:
        """One message through the intake, counted and logged (a drain's step)."""
        got = self.intake.take(frames)
        if isinstance(got, Taken):
            if got.seq.status in (SeqStatus.GAP, SeqStatus.RESTART):
                self._seqlog.note(got.seq.status, got.msg.seq, got.seq.missing)
        elif got.kind == "duplicate":
            self._seqlog.note(None, got.msg.seq if got.msg is not None else 0)
        else:
            self.bad.count(got.kind, got.detail)
        return got

    def unexpected(self, what: str) -> None:
        """Count a taken message its user cannot serve after all (a stage cue with no stage)."""
        self.intake.bad["unexpected"] += 1
        self.bad.unexpected(what)

    @property
    def counts(self) -> Counts:
        seq = self.intake.seq
        return Counts(
            seq.received, seq.missing, seq.duplicates, seq.restarts, self.intake.bad_total
        )

    def close(self) -> None:
        """Close the socket; log the bad-message totals and any loss line still unsaid."""
        if self.sock is not None:
            self.sock.close(0)
            self.sock = None
        self._seqlog.flush()
        self.bad.log_summary()
