"""Sequence tracking: what a subscriber learns from the per-stream sequence numbers.

Every message on a (performer, stream) takes the next number, so a receiver sees loss
(including at the tail, through heartbeats), duplicates and sender restarts (a jump back to
0) without any extra message.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from livedrummer.protocol.bodies import Message


class SeqStatus(IntEnum):
    FIRST = 0  # first message seen on this stream
    OK = 1  # the expected next number
    GAP = 2  # numbers were skipped: ``missing`` messages lost
    DUPLICATE = 3  # an old number again (dropped by the caller)
    RESTART = 4  # 0 after higher numbers: the sender restarted


@dataclass(frozen=True, slots=True)
class SeqReport:
    status: SeqStatus
    missing: int = 0


@dataclass
class SeqStats:
    received: int = 0
    missing: int = 0
    duplicates: int = 0
    restarts: int = 0


class SequenceTracker:
    """Gap and duplicate detection per (performer, stream).

    A receiver joining mid-stream starts from whatever number it sees first (FIRST). ZeroMQ
    delivers in order on one connection, so a smaller number than expected is a duplicate,
    except 0, which means the sender restarted.
    """

    def __init__(self) -> None:
        self._next: dict[tuple[int, int], int] = {}
        self.stats: dict[tuple[int, int], SeqStats] = {}

    def reset(self) -> None:
        self._next.clear()
        self.stats.clear()

    def observe(self, performer: int, stream: int, seq: int) -> SeqReport:
        key = (performer, stream)
        stats = self.stats.setdefault(key, SeqStats())
        expected = self._next.get(key)
        if expected is None:
            report = SeqReport(SeqStatus.FIRST)
        elif seq == expected:
            report = SeqReport(SeqStatus.OK)
        elif seq > expected:
            report = SeqReport(SeqStatus.GAP, seq - expected)
            stats.missing += seq - expected
        elif seq == 0:
            report = SeqReport(SeqStatus.RESTART)
            stats.restarts += 1
        else:
            stats.duplicates += 1
            return SeqReport(SeqStatus.DUPLICATE)
        stats.received += 1
        self._next[key] = seq + 1
        return report

    def observe_message(self, msg: Message) -> SeqReport:
        return self.observe(msg.performer, msg.stream, msg.seq)
