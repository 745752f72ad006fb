"""The computer keyboard as a drum kit: which key plays which General MIDI drum note, how loud.

Someone without an e-kit can still play the drummer: the windows (the file window and the live
window) look every key press up in :data:`KEYPADS` and play the note it names. The layout
keeps the feet and the snare on the bottom row under the left hand (Z kick, X snare, C side
stick, V hi-hat pedal), the hi-hat above them (T closed, Y open), the toms under the right
hand (N, J, K from high to floor) and the cymbals on the top row (U crash, P ride, E ride bell
... see :data:`KEYPADS`). Keys the windows already use (space, arrows, Home/End, R = - 0 M [ ]
A B L S H I F Q O G, Escape and the digits) are left out, so transport and cameras still work
while playing. A plain press is :data:`MEDIUM`; Shift is an accent (:data:`LOUD`) and Ctrl a
ghost note (:data:`SOFT`).

The notes are General MIDI's percussion notes, so the default ``general-midi`` note map (and
any GM sound module) reads them as the pieces named here. Limits: a keyboard has no velocity
and most keyboards report only a few keys at once; key repeat is not a roll (the windows play
only the first press).
"""

from __future__ import annotations

from dataclasses import dataclass

MEDIUM = 80  #: velocity of a plain key press
LOUD = 120  #: velocity with Shift held (an accent)
SOFT = 40  #: velocity with Ctrl held (a ghost note)


@dataclass(frozen=True)
class Keypad:
    """One key of the layout: the GM drum note it plays and what to call it in the help."""

    key: str  # the window's key name (lower-case letter or punctuation name)
    note: int
    label: str


#: key name -> what it plays (the order is the order of the help lines)
KEYPADS: dict[str, Keypad] = {
    k.key: k
    for k in (
        Keypad("z", 36, "KICK"),
        Keypad("x", 38, "SNARE"),
        Keypad("c", 37, "SNARE RIM"),
        Keypad("v", 44, "HI-HAT PEDAL"),
        Keypad("t", 42, "HI-HAT CLOSED"),
        Keypad("y", 46, "HI-HAT OPEN"),
        Keypad("n", 50, "HIGH TOM"),
        Keypad("j", 48, "MID TOM"),
        Keypad("k", 43, "FLOOR TOM"),
        Keypad("u", 49, "CRASH"),
        Keypad("p", 51, "RIDE"),
        Keypad("e", 53, "RIDE BELL"),
    )
}

#: keys the windows use for something else; the layout must never take one
RESERVED: frozenset[str] = frozenset(
    "space right left home end escape equal minus kp_add kp_subtract left_bracket "
    "right_bracket r m a b l s h i f q o g 0 1 2 3 4 5 6 7 8 9".split()
)


def velocity_for(shift: bool, ctrl: bool) -> int:
    """The velocity of a press with these modifiers (Shift wins over Ctrl)."""
    if shift:
        return LOUD
    return SOFT if ctrl else MEDIUM


def keypad_hit(key: str, shift: bool = False, ctrl: bool = False) -> tuple[int, int] | None:
    """``(note, velocity)`` for a press of ``key``, or None when the key plays nothing."""
    pad = KEYPADS.get(key)
    return None if pad is None else (pad.note, velocity_for(shift, ctrl))


def help_lines() -> list[str]:
    """The layout for the windows' key help (upper-case, as the 5x7 font draws)."""
    pads = [f"{p.key.upper()} {p.label}" for p in KEYPADS.values()]
    lines = ["KEYS PLAY THE KIT (SHIFT LOUD, CTRL SOFT):"]
    for i in range(0, len(pads), 4):
        lines.append("  " + "   ".join(pads[i : i + 4]))
    return lines
