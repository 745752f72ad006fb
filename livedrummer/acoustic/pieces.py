"""The drum classes the recogniser tells apart, and how a MIDI onset maps onto them.

Nine classes: the pieces whose sounds differ enough to be told apart from a mix (kick,
snare, closed and open hi-hat, three toms by pitch, crash, ride). Every kit instrument falls
into one of them (:func:`class_of`): the cymbals other than the ride sound as a crash, toms
4-6 as the low tom. A hi-hat pedal chick (zone ``pedal``) has no class: it is too quiet to
hear in a mix, so it is "don't care" when scoring. Each class is written to MIDI as one
General MIDI note (:data:`GM_NOTES`), on channel 10.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone

CLASSES: tuple[str, ...] = (
    "kick",
    "snare",
    "hihat_closed",
    "hihat_open",
    "tom_high",
    "tom_mid",
    "tom_low",
    "crash",
    "ride",
)
CLASS_CODE: dict[str, int] = {name: i for i, name in enumerate(CLASSES)}
#: General MIDI percussion note that each class is written as (same order as CLASSES).
GM_NOTES: tuple[int, ...] = (36, 38, 42, 46, 50, 48, 45, 49, 51)
#: Kit instrument (note-map role) and hi-hat articulation each class stands for on the bus.
CLASS_INSTRUMENT: tuple[str, ...] = (
    "kick",
    "snare",
    "hihat",
    "hihat",
    "tom1",
    "tom2",
    "tom3",
    "crash1",
    "ride",
)
NO_CLASS = -1

_BY_INSTRUMENT = {
    "kick": "kick", "snare": "snare", "tom1": "tom_high", "tom2": "tom_mid", "tom3": "tom_low",
    "tom4": "tom_low", "tom5": "tom_low", "tom6": "tom_low", "crash1": "crash",
    "crash2": "crash", "splash": "crash", "china": "crash", "ride": "ride",
}  # fmt: skip


def class_of(instrument: str, zone: Zone, hihat: HiHat) -> int:
    """The class code of a stroke, or :data:`NO_CLASS` (pedal chick, hand percussion)."""
    if instrument == "hihat":
        if zone is Zone.PEDAL or hihat is HiHat.PEDAL:
            return NO_CLASS
        opened = hihat in (HiHat.OPEN, HiHat.HALF)
        return CLASS_CODE["hihat_open" if opened else "hihat_closed"]
    name = _BY_INSTRUMENT.get(instrument)
    return NO_CLASS if name is None else CLASS_CODE[name]


def classes_of(onsets: np.ndarray) -> np.ndarray:
    """:func:`class_of` of every row of an onset array (int16; -1 = no class)."""
    out = np.full(len(onsets), NO_CLASS, np.int16)
    for i, o in enumerate(onsets):
        out[i] = class_of(
            INSTRUMENTS[int(o["instrument"])], ZONES[int(o["zone"])], HIHATS[int(o["hihat"])]
        )
    return out


def parse_class(name: str, where: str) -> int:
    """A class code from its name (``hihat`` is accepted for the closed hi-hat)."""
    alias = {"hihat": "hihat_closed", "hh": "hihat_closed", "tom": "tom_mid"}
    key = alias.get(name.strip().lower(), name.strip().lower())
    if key not in CLASS_CODE:
        from livedrummer.errors import LivedrummerError

        raise LivedrummerError(
            f"{where}: unknown drum {name!r} (one of {', '.join(CLASSES)}, or hihat)"
        )
    return CLASS_CODE[key]


def parse_channel_map(spec: str, where: str = "--channels") -> dict[int, int]:
    """``1=kick,2=snare,3=hihat`` → {0-based input channel: class code}."""
    from livedrummer.errors import LivedrummerError

    out: dict[int, int] = {}
    for item in (x.strip() for x in spec.split(",")):
        number, sep, name = item.partition("=")
        if not sep or not number.strip().isdigit() or int(number) < 1:
            raise LivedrummerError(
                f"{where}: {item!r} is not CHANNEL=DRUM (e.g. 1=kick,2=snare; channels from 1)"
            )
        if int(number) - 1 in out:
            raise LivedrummerError(f"{where}: channel {int(number)} named twice")
        out[int(number) - 1] = parse_class(name, where)
    return out
