"""The onset-source interface: thin backends behind one small base.

Why this shape. A MIDI port, a serial trigger board, a file played as if performed and a
remote site's stream differ only in how bytes arrive. Each backend implements ``open``,
``read(timeout_s)`` and ``close``; everything else (decoding MIDI into onsets with the shared
:class:`~livedrummer.midi.decode.MessageDecoder`, counting problems, the reconnect loop, publishing
and journaling) lives once, in the base and the daemon. ``read`` returns events already
stamped on the shared clock *at arrival* (in the device callback, or right after the read
that delivered the bytes), decoded into :class:`Onset`, :class:`Control` or :class:`Gap`.

Errors: a backend raises :class:`~livedrummer.errors.MidiInputError` when its device is absent
or fails; the daemon then closes it, reports the problem once (with a count) and reopens it
until it returns. Nothing a device sends can raise anything else. Before a show starts,
:meth:`Source.check` says at once, in one line naming what exists, that a device is not
there (the CLI exits 2 on it unless ``--wait`` asks to wait for the device).

Watching. A :class:`MidiSource` calls its ``tap`` (when set) with every channel message as
it arrives, before decoding: ``livedrummer monitor`` prints what the kit sends from there.
"""

from __future__ import annotations

import logging
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

from livedrummer.midi.decode import MessageDecoder
from livedrummer.protocol import Gap
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import Control, Onset
from livedrummer.timeline.stats import DecodeStats

log = logging.getLogger("livedrummer.input")

Event = Onset | Control | Gap

_KINDS = {
    0x80: "note_off",
    0x90: "note_on",
    0xA0: "polytouch",
    0xB0: "control_change",
    0xC0: "program_change",
    0xD0: "aftertouch",
    0xE0: "pitchwheel",
}


@dataclass(slots=True)
class RawMidi:
    """A channel message in the shape :class:`MessageDecoder` reads (like ``mido.Message``)."""

    type: str
    channel: int
    note: int = 0
    velocity: int = 0
    control: int = 0
    value: int = 0

    @classmethod
    def from_bytes(cls, status: int, data: bytes | list[int]) -> RawMidi | None:
        """Channel voice message from its status and data bytes; None for anything else."""
        kind = _KINDS.get(status & 0xF0) if 0x80 <= status < 0xF0 else None
        if kind is None or len(data) < (1 if status & 0xF0 in (0xC0, 0xD0) else 2):
            return None
        ch = status & 0x0F
        d0 = data[0]
        d1 = data[1] if len(data) > 1 else 0
        if kind in ("note_on", "note_off"):
            return cls(kind, ch, note=d0, velocity=d1)
        if kind == "polytouch":
            return cls(kind, ch, note=d0, value=d1)
        if kind == "control_change":
            return cls(kind, ch, control=d0, value=d1)
        return cls(kind, ch, value=d0)


class Problems:
    """Counts problems by kind and logs each kind once (then only its count at the end)."""

    def __init__(self) -> None:
        self.counts: Counter[str] = Counter()

    def report(self, kind: str, detail: str, n: int = 1) -> None:
        """Count ``n`` occurrences of ``kind``; log ``detail`` the first time only."""
        first = kind not in self.counts
        self.counts[kind] += n
        if first:
            log.warning("%s: %s (further ones counted, not logged)", kind, detail)

    def summary(self) -> dict[str, int]:
        return dict(self.counts)


class Source(ABC):
    """One onset source; see the module docstring."""

    #: Set by sources that replay (file) or relay (remote) rather than capture a performance.
    simulated = False
    relayed = False

    def __init__(self, name: str, clock: Clock, problems: Problems | None = None) -> None:
        self.name = name
        self.clock = clock
        self.problems = problems if problems is not None else Problems()
        self.is_open = False

    @abstractmethod
    def open(self) -> None:
        """Open the device; raise MidiInputError if it is absent."""

    @abstractmethod
    def read(self, timeout_s: float) -> list[Event]:
        """Events that arrived, waiting at most ``timeout_s`` for the first one."""

    @abstractmethod
    def close(self) -> None:
        """Release the device; safe to call twice."""

    def check(self) -> None:  # noqa: B027 (optional hook: files and streams have no device)
        """Raise MidiInputError naming the device and what exists if it is not there now."""

    def finished(self) -> bool:
        """True when the source has nothing more to give (a file played to its end)."""
        return False

    def decode_stats(self) -> DecodeStats | None:
        """What the MIDI decoder counted (unknown notes, duplicates), if this source decodes."""
        return None


class MidiSource(Source):
    """A source of raw MIDI bytes: decodes them with the shared decoder."""

    def __init__(
        self, name: str, clock: Clock, decoder: MessageDecoder, problems: Problems | None = None
    ) -> None:
        super().__init__(name, clock, problems)
        self.decoder = decoder
        #: Called with (stamp, message) for every channel message, before decoding.
        self.tap: Callable[[float, RawMidi], None] | None = None

    def decode_stats(self) -> DecodeStats | None:
        return self.decoder.stats

    def decode(self, time_s: float, status: int, data: bytes | list[int], out: list[Event]) -> None:
        raw = RawMidi.from_bytes(status, data)
        if raw is None:
            return
        if self.tap is not None:
            self.tap(time_s, raw)
        event = self.decoder.feed(time_s, raw)
        if event is not None:
            out.append(event)
