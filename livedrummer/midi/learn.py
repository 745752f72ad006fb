"""Mapping a new module by hitting it: the prompts, what each hit taught, the note map written.

``livedrummer map learn`` asks for each pad and zone in turn (snare head, snare rim, ...,
the hi-hat pedal) and the drummer hits it, or skips it. :class:`MapLearner` is that session
as pure logic: :attr:`MapLearner.prompt` is the pad asked for now; :meth:`MapLearner.feed`
takes every channel message that arrives; the first note-on for a prompt is that pad's note
(a note already learned for another pad is refused with the reason, so a double-triggering
pad cannot map two zones onto one note); the hi-hat pedal prompt records the range of the
pedal controller (CC4 by default) while the drummer opens and closes it, and, if it comes,
the foot-chick note (the pedal's range is recorded whenever it moves); aftertouch on a learned
cymbal note marks that the module sends chokes. :meth:`MapLearner.toml` writes a note map that
:func:`~livedrummer.midi.notemap.load_note_map` loads, with where it came from in its header.

Limits: one note per prompt. A module that sends several notes for one hit (a DTX-PRO input
with more than one of its Note.1-4 set) teaches the first; the others, arriving within
:data:`SAME_HIT_S` of it, are reported as part of that hit, not taken as the next pad's;
the pedal's closed value is the largest controller value seen (modules send 0 open ... N
closed); a pad the drummer skips is simply absent from the map (``inspect`` then reports its
notes as unknown).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from livedrummer.midi.decode import ChannelMessage

#: A note this soon after the note that answered a prompt comes from the same hit: modules send
#: a hit's notes back to back (a MIDI message takes 1 ms on a DIN cable), a drummer reaches the
#: next pad after reading its prompt, hundreds of milliseconds later.
SAME_HIT_S = 0.010

#: (piece, zone, hi-hat state or "", label): the prompts of a five-piece kit with three
#: cymbals, in the order a drummer goes round the kit.
PROMPTS: tuple[tuple[str, str, str, str], ...] = (
    ("kick", "head", "", "Kick"),
    ("snare", "head", "", "Snare head"),
    ("snare", "rim", "", "Snare rim (rim shot)"),
    ("snare", "cross_stick", "", "Snare cross stick"),
    ("hihat", "bow", "closed", "Hi-hat closed (bow)"),
    ("hihat", "edge", "closed", "Hi-hat closed (edge)"),
    ("hihat", "bow", "open", "Hi-hat open (bow)"),
    ("hihat", "edge", "open", "Hi-hat open (edge)"),
    ("hihat", "pedal", "pedal", "Hi-hat pedal (close it, open it, close it)"),
    ("tom1", "head", "", "Tom 1"),
    ("tom1", "rim", "", "Tom 1 rim"),
    ("tom2", "head", "", "Tom 2"),
    ("tom2", "rim", "", "Tom 2 rim"),
    ("tom3", "head", "", "Tom 3 (floor)"),
    ("tom3", "rim", "", "Tom 3 rim"),
    ("crash1", "bow", "", "Crash 1 (bow)"),
    ("crash1", "edge", "", "Crash 1 (edge)"),
    ("crash2", "bow", "", "Crash 2 (bow)"),
    ("crash2", "edge", "", "Crash 2 (edge)"),
    ("ride", "bow", "", "Ride (bow)"),
    ("ride", "edge", "", "Ride (edge)"),
    ("ride", "bell", "", "Ride (bell)"),
)


@dataclass
class Learned:
    """What one prompt taught: its note (None: skipped)."""

    piece: str
    zone: str
    hihat: str
    label: str
    note: int | None = None


@dataclass
class MapLearner:
    """One learning session (see the module docstring)."""

    name: str
    source: str = ""  # the port or device, for the header
    hihat_cc: int = 4
    prompts: tuple[tuple[str, str, str, str], ...] = PROMPTS
    done: list[Learned] = field(default_factory=list)
    cc_values: list[int] = field(default_factory=list)
    chokes: bool = False
    answered_s: float | None = None  # when the last prompt was answered by a note

    @property
    def prompt(self) -> tuple[str, str, str, str] | None:
        """The pad asked for now; None when every prompt has been answered."""
        i = len(self.done)
        return self.prompts[i] if i < len(self.prompts) else None

    def _answer(self, note: int | None) -> None:
        piece, zone, hihat, label = self.prompts[len(self.done)]
        self.done.append(Learned(piece, zone, hihat, label, note))

    def skip(self) -> None:
        if self.prompt is not None:
            self._answer(None)

    def notes(self) -> dict[int, Learned]:
        return {d.note: d for d in self.done if d.note is not None}

    def feed(self, msg: ChannelMessage, time_s: float | None = None) -> str | None:
        """One message (``time_s``: when it came, seconds on any clock; None: no same-hit
        check); returns a line for the drummer when it answered or was refused."""
        prompt = self.prompt
        if msg.type == "control_change" and msg.control == self.hihat_cc:
            self.cc_values.append(msg.value)  # the pedal moves during the hi-hat prompts too
            return None
        if msg.type == "polytouch":
            if msg.note in self.notes():
                self.chokes = True
            return None
        if msg.type != "note_on" or msg.velocity == 0 or prompt is None:
            return None
        if time_s is not None and self.answered_s is not None:
            if time_s - self.answered_s < SAME_HIT_S:
                last = next(d for d in reversed(self.done) if d.note is not None)
                return (
                    f"note {msg.note} came in the same hit as note {last.note} ({last.label}): "
                    "not learned; a pad sending several notes teaches the first (turn the "
                    "others off on the module to learn them apart)"
                )
        known = self.notes()
        if msg.note in known:
            if prompt[1] == "pedal" and known[msg.note].piece != "hihat":
                return None
            return (
                f"note {msg.note} is already {known[msg.note].label}: hit {prompt[3]} "
                "again, or skip it"
            )
        self._answer(msg.note)
        self.answered_s = time_s
        return f"{prompt[3]}: note {msg.note}"

    def finish_pedal(self) -> str | None:
        """Close the pedal prompt on the controller range alone (a module with no chick note)."""
        prompt = self.prompt
        if prompt is None or prompt[1] != "pedal" or not self.cc_values:
            return None
        self._answer(None)
        lo, hi = min(self.cc_values), max(self.cc_values)
        return f"hi-hat pedal: controller {self.hihat_cc}, {lo}..{hi}"

    def closed_value(self) -> int:
        """The pedal controller's value when closed: the largest seen (127 if none)."""
        return max(self.cc_values) if self.cc_values and max(self.cc_values) > 0 else 127

    def toml(self) -> str:
        """The note map as TOML text (see the module docstring)."""
        lines = [
            f"# Note map learned by `livedrummer map learn` from {self.source or 'a module'}.",
            f"# Skipped: {', '.join(d.label for d in self.done if d.note is None) or 'nothing'}.",
            f"# Chokes (aftertouch on cymbal notes): {'seen' if self.chokes else 'not seen'}.",
            "",
            "[map]",
            f'name = "{self.name}"',
            f'description = "learned from {self.source or "a module"}"',
            f"hihat_cc = {self.hihat_cc}",
            f"hihat_cc_closed = {self.closed_value()}",
            "",
            "[notes]",
        ]
        for d in self.done:
            if d.note is None:
                continue
            hihat = f'hihat = "{d.hihat}", ' if d.piece == "hihat" else ""
            lines.append(
                f'{d.note} = {{ piece = "{d.piece}", zone = "{d.zone}", {hihat}'
                f'label = "{d.label}" }}'
            )
        return "\n".join(lines) + "\n"
