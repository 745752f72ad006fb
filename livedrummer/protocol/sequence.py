"""Sequence tracking: what a subscriber learns from the per-stream sequence numbers.

Every message on a (performer, stream) takes the next number (heartbeats too), and the sender
stamps its send time on the shared clock. From those two header fields alone, with no extra
message, a receiver tells apart the four things that happen to a ZeroMQ stream. This module
is the one place that decides which is which; every subscriber reads it through
:class:`SequenceTracker` (and the services through ``services.wire.stream_rx``).

The policy, per (performer, stream), against ``expected`` (the number after the last
message taken) and the newest send time taken:

    first      nothing taken yet: take it, count nothing (a receiver joining mid-stream
               starts from whatever number it sees first)
    ok         seq == expected: take it
    gap        seq > expected: take it; ``seq - expected`` messages are missing (lost past
               a high-water mark, a dropped connection, the sender's own shedding)
    restart    seq < expected and either seq == 0 or the send time is newer than every
               message taken: the sender started numbering again (a restarted synth or
               input daemon; one we reconnected to after its first messages shows a small
               number with a fresh send time). Take it and start over from it: nothing of
               the new run before it is counted missing (as for ``first``)
    duplicate  seq < expected, seq != 0, send time not newer, and within
               :data:`REORDER_WINDOW` of expected: an old number again or one out of order
               (two paths to one receiver, a misconfigured relay). Drop it and count it;
               a number counted missing stays missing even if it turns up late
    restart    also when seq is more than :data:`REORDER_WINDOW` behind, whatever its send
               time: no reorder is that deep, so the sender must have started again

This follows the ZeroMQ guide's Clone client (an update whose number is not above the one it
holds is discarded), and adds what a stream without snapshots needs: a restart is seen in the
stream itself, and the caller is told (``RESTART``) so it can drop state of the old run, as a
Clone client would fetch a fresh snapshot.

Limits. ZeroMQ keeps order on one connection, so duplicates and reorders need two paths;
the policy cannot tell which of two live senders on one (performer, stream) is right (their
numbers interleave as restarts and duplicates: two synths with one ``--performer`` show as a
stream of restarts). A sender whose clock went back (another machine rebooted) and which we
rejoin after its first messages, within ``REORDER_WINDOW`` of the old numbers, has up to that
many messages dropped as duplicates before its numbers pass the old ones. A receiver that
filters kinds (a subscription to two kinds only) sees the others' numbers as gaps, so such a
receiver must not count them (``services.wire.stream_rx`` has ``sequenced=False``).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from livedrummer.protocol.bodies import Message

#: How far behind ``expected`` a number may be and still be a reorder or duplicate (dropped)
#: rather than a sender that started again (taken).
REORDER_WINDOW = 64


class SeqStatus(IntEnum):
    FIRST = 0  # first message seen on this stream: taken
    OK = 1  # the expected next number: taken
    GAP = 2  # numbers were skipped: ``missing`` messages lost; taken
    DUPLICATE = 3  # an old number again, or one out of order: dropped
    RESTART = 4  # the sender started numbering again: taken, counting starts over


@dataclass(frozen=True, slots=True)
class SeqReport:
    status: SeqStatus
    missing: int = 0

    @property
    def taken(self) -> bool:
        """False for a duplicate or reordered message: the policy drops it."""
        return self.status is not SeqStatus.DUPLICATE


@dataclass
class SeqStats:
    received: int = 0  # messages taken (a dropped duplicate is not received)
    missing: int = 0
    duplicates: int = 0
    restarts: int = 0

    def add(self, other: SeqStats) -> None:
        self.received += other.received
        self.missing += other.missing
        self.duplicates += other.duplicates
        self.restarts += other.restarts


@dataclass
class _Cursor:
    expected: int
    newest_send_s: float


class SequenceTracker:
    """The policy of the module docstring, per (performer, stream)."""

    def __init__(self) -> None:
        self._at: dict[tuple[int, int], _Cursor] = {}
        self.stats: dict[tuple[int, int], SeqStats] = {}

    def reset(self) -> None:
        self._at.clear()
        self.stats.clear()

    def totals(self) -> SeqStats:
        """The counts summed over every (performer, stream) seen."""
        out = SeqStats()
        for stats in self.stats.values():
            out.add(stats)
        return out

    def observe(self, performer: int, stream: int, seq: int, send_time_s: float = 0.0) -> SeqReport:
        key = (performer, stream)
        stats = self.stats.setdefault(key, SeqStats())
        at = self._at.get(key)
        if at is None:
            report = SeqReport(SeqStatus.FIRST)
        elif seq == at.expected:
            report = SeqReport(SeqStatus.OK)
        elif seq > at.expected:
            report = SeqReport(SeqStatus.GAP, seq - at.expected)
            stats.missing += report.missing
        elif seq == 0 or send_time_s > at.newest_send_s or at.expected - seq > REORDER_WINDOW:
            report = SeqReport(SeqStatus.RESTART)
            stats.restarts += 1
        else:
            stats.duplicates += 1
            return SeqReport(SeqStatus.DUPLICATE)
        stats.received += 1
        if at is None or report.status is SeqStatus.RESTART:
            self._at[key] = _Cursor(seq + 1, send_time_s)
        else:
            at.expected = seq + 1
            at.newest_send_s = max(at.newest_send_s, send_time_s)
        return report

    def observe_message(self, msg: Message) -> SeqReport:
        return self.observe(msg.performer, msg.stream, msg.seq, msg.send_time_s)
