"""One subscriber's intake: frames in, a taken message or a counted drop out (no sockets).

Why one class. Every subscriber of a livedrummer stream (the synth reading an input daemon,
the live and stage displays reading a synth, the practice rig and a remote jam reading an
input daemon, the display's sound process) does the same four steps to each message, and they
had drifted apart when each wrote them itself. :class:`StreamIntake` does them once, in this
order, so that the order is the same everywhere too:

1. :func:`~livedrummer.protocol.decode` (with the stream's pose format, where it has poses);
   a :class:`~livedrummer.errors.ProtocolError` becomes a drop of the kind :func:`kind_of`
   names;
2. the kind: one the subscriber does not serve (a HELLO on a pose stream) is an
   ``unexpected`` drop;
3. the performer, where the stream is one performer's (the stage display): a message of
   another is an ``unexpected`` drop, never drawn on the wrong drummer;
4. the sequence number, by the one policy of :mod:`~livedrummer.protocol.sequence`: a
   duplicate or reordered message is dropped (counted as a duplicate, not as bad), a gap or
   a restart is reported with the message, which is taken.

A bad message is dropped before its sequence number is read, so junk never shows as loss
or as a restart. :attr:`StreamIntake.bad` counts drops by kind; the I/O side
(``services.wire.stream_rx``) reads sockets, logs and feeds this class.

Kinds of drop, from the ``field`` a :class:`~livedrummer.protocol.WireError` names:

    version    the header's version byte is not ours
    header     header frame of the wrong size (truncated, random bytes), bad magic, unknown
               kind, or header values out of range (flags, performer, stream, seq, send time)
    oversized  payload_len above the receiver's limit (``max_payload``)
    size       payload_len disagrees with the bytes in the payload frames
    frames     no frames, or the wrong number of frames for the kind (multi-frame garbage)
    payload    the payload itself is invalid (rows out of range, bad HELLO JSON, pose hash)
    unexpected a valid message of a kind (or performer) this subscriber does not serve
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from livedrummer.errors import ProtocolError
from livedrummer.protocol.bodies import Message
from livedrummer.protocol.codec import decode
from livedrummer.protocol.poseformat import PoseFormat
from livedrummer.protocol.sequence import SeqReport, SeqStats, SeqStatus, SequenceTracker
from livedrummer.protocol.spec import MAX_PAYLOAD, Kind

KINDS = ("version", "header", "oversized", "size", "frames", "payload", "unexpected")

_HEADER_FIELDS = frozenset(
    ("header", "magic", "kind", "flags", "performer", "stream", "seq", "send_time_s")
)


def kind_of(exc: ProtocolError) -> str:
    """The short kind of a decode error (see the module docstring)."""
    name = getattr(exc, "field", "")
    if not isinstance(name, str):
        return "payload"
    if name == "version":
        return "version"
    if name == "max_payload":
        return "oversized"
    if name == "payload_len":
        return "size"
    if name == "frames" or name.startswith("frame "):
        return "frames"
    if name in _HEADER_FIELDS:
        return "header"
    return "payload"


@dataclass(frozen=True, slots=True)
class Taken:
    """A message the subscriber should act on, with what its number said."""

    msg: Message
    seq: SeqReport


@dataclass(frozen=True, slots=True)
class Dropped:
    """A message not acted on: ``kind`` one of :data:`KINDS`, or ``"duplicate"``."""

    kind: str
    detail: str
    msg: Message | None = None  # the decoded message, where it decoded


class StreamIntake:
    """Decode, filter by kind and performer, observe the number (see the module docstring).

    ``kinds``: the kinds served (others are ``unexpected``). ``performer``: the one performer
    served (None: any). ``sequenced=False`` skips step 4, for a subscriber that filters kinds
    in its subscription and so cannot read the numbers (every message is then taken).
    """

    def __init__(
        self,
        kinds: Iterable[Kind],
        pose_format: PoseFormat | None = None,
        performer: int | None = None,
        sequenced: bool = True,
        max_payload: int = MAX_PAYLOAD,
    ) -> None:
        self.kinds = frozenset(kinds)
        self.pose_format = pose_format
        self.performer = performer
        self.sequenced = sequenced
        self.max_payload = max_payload
        self.tracker = SequenceTracker()
        self.bad: Counter[str] = Counter()

    def take(self, frames: Sequence[object]) -> Taken | Dropped:
        """One message's frames, through the four steps."""
        try:
            msg = decode(frames, self.pose_format, self.max_payload)
        except ProtocolError as exc:
            return self._drop(kind_of(exc), str(exc))
        if msg.kind not in self.kinds:
            return self._drop("unexpected", f"{msg.kind.name} is not served here", msg)
        if self.performer is not None and msg.performer != self.performer:
            return self._drop(
                "unexpected",
                f"{msg.kind.name} of performer {msg.performer} "
                f"(this stream is performer {self.performer}'s)",
                msg,
            )
        if not self.sequenced:
            return Taken(msg, _UNSEQUENCED)
        report = self.tracker.observe_message(msg)
        if not report.taken:
            return Dropped("duplicate", f"#{msg.seq} again or out of order", msg)
        return Taken(msg, report)

    def _drop(self, kind: str, detail: str, msg: Message | None = None) -> Dropped:
        self.bad[kind] += 1
        return Dropped(kind, detail, msg)

    @property
    def seq(self) -> SeqStats:
        """Sequence counts summed over the (performer, stream) pairs seen."""
        return self.tracker.totals()

    @property
    def bad_total(self) -> int:
        return sum(self.bad.values())


_UNSEQUENCED = SeqReport(SeqStatus.OK)
