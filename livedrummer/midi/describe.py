"""What one MIDI message means on a kit, in words and as a record: ``livedrummer monitor``.

A drummer setting up a module wants to see, hit by hit, what the kit sends and what we make
of it: the note and its velocity, the piece and zone the note map gives it (or that it is
unknown, or a sound the map deliberately ignores), the hi-hat pedal's controller value and
the openness it means, aftertouch chokes and on which piece. :func:`describe` answers that
for one channel message and a note map, with no state, so the monitor can print it as the
message arrives (a line, :meth:`MessageInfo.line`, or JSON, :meth:`MessageInfo.to_json`).

Limits: it describes the message alone; what the decoder does *across* messages (the
pedal's state under a hi-hat note, a double within 1 ms dropped) is the decoder's, and the
monitor shows the decoded hi-hat state only through the pedal lines before it. Channels are
printed 1..16, as modules label them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from livedrummer.midi.decode import ChannelMessage
from livedrummer.midi.notemap import NoteMap

#: Controllers drummers meet, by number (anything else is printed by number only).
CC_NAMES = {
    1: "modulation",
    4: "hi-hat pedal",
    7: "volume",
    16: "strike position",
    17: "strike position",
    18: "strike position",
    64: "sustain",
}


@dataclass(frozen=True)
class MessageInfo:
    """One message and its meaning (see the module docstring)."""

    time_s: float
    type: str
    channel: int  # 1..16
    number: int  # note or controller number (0 for other types)
    value: int  # velocity, controller value or pressure
    meaning: str  # "snare head", "unknown note", "hi-hat pedal 0.42 open", ...
    known: bool  # False for a note (or choke) the map does not know

    def line(self, start_s: float = 0.0) -> str:
        what = {
            "note_on": "note",
            "note_off": "off",
            "control_change": "CC",
            "polytouch": "touch",
        }.get(self.type, self.type)
        mark = "  " if self.known else "? "
        return (
            f"{self.time_s - start_s:9.3f} s  ch{self.channel:<2d} {what:<5} "
            f"{self.number:3d} {self.value:3d}  {mark}{self.meaning}"
        )

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


def describe(time_s: float, msg: ChannelMessage, note_map: NoteMap) -> MessageInfo:
    """The meaning of one channel message under ``note_map``."""
    kind, ch = msg.type, msg.channel + 1
    if kind == "note_on" and msg.velocity > 0:
        spec = note_map.lookup(msg.note)
        if spec is not None:
            return MessageInfo(time_s, kind, ch, msg.note, msg.velocity, spec.label, True)
        if msg.note in note_map.ignored:
            label = note_map.ignored[msg.note]
            return MessageInfo(
                time_s,
                kind,
                ch,
                msg.note,
                msg.velocity,
                f"{label} (ignored: not on a drum kit)",
                True,
            )
        return MessageInfo(
            time_s,
            kind,
            ch,
            msg.note,
            msg.velocity,
            f"unknown note (not in map {note_map.name})",
            False,
        )
    if kind in ("note_on", "note_off"):
        return MessageInfo(time_s, "note_off", ch, msg.note, msg.velocity, "release", True)
    if kind == "control_change":
        if msg.control == note_map.hihat_cc:
            openness = note_map.openness(msg.value)
            meaning = f"hi-hat pedal: {openness:.2f} open"
        else:
            meaning = CC_NAMES.get(msg.control, "controller (not used)")
        return MessageInfo(time_s, kind, ch, msg.control, msg.value, meaning, True)
    if kind == "polytouch":
        spec = note_map.lookup(msg.note)
        if spec is None:
            return MessageInfo(
                time_s, kind, ch, msg.note, msg.value, "aftertouch on an unknown note", False
            )
        meaning = f"choke: {spec.instrument}" if msg.value else "choke released"
        return MessageInfo(time_s, kind, ch, msg.note, msg.value, meaning, True)
    return MessageInfo(time_s, kind, ch, 0, getattr(msg, "value", 0), "not used", True)
