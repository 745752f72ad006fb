"""The fixed words every other module speaks: instruments, zones, hi-hat states and limbs.

Note maps translate MIDI note numbers into an *instrument* (a role such as ``tom2`` or
``crash1``) and a *zone* (where on that instrument the stick lands). Kits then say which of
their physical pieces plays each instrument. Keeping this vocabulary closed and small is what
lets any map drive any kit, and lets onsets be stored as compact integer codes in numpy arrays:
an instrument or zone code is its index in the tuples below, so the order is part of the wire
format and must only ever be appended to.
"""

from __future__ import annotations

from enum import StrEnum

#: Instrument roles a note map may name, in code order (index = code in onset arrays).
INSTRUMENTS: tuple[str, ...] = (
    "kick", "snare", "hihat",
    "tom1", "tom2", "tom3", "tom4", "tom5", "tom6",
    "crash1", "crash2", "ride", "splash", "china",
    "cowbell", "tambourine", "percussion",
)  # fmt: skip
INSTRUMENT_CODE: dict[str, int] = {name: i for i, name in enumerate(INSTRUMENTS)}


class PieceKind(StrEnum):
    """What a physical kit piece is; decides its zones and how it is drawn and struck."""

    KICK = "kick"
    SNARE = "snare"
    TOM = "tom"
    HIHAT = "hihat"
    CRASH = "crash"
    RIDE = "ride"
    SPLASH = "splash"
    CHINA = "china"
    COWBELL = "cowbell"
    TAMBOURINE = "tambourine"
    PERCUSSION = "percussion"

    @property
    def is_cymbal(self) -> bool:
        return self in _CYMBALS


_CYMBALS = frozenset(
    {PieceKind.HIHAT, PieceKind.CRASH, PieceKind.RIDE, PieceKind.SPLASH, PieceKind.CHINA}
)


class Zone(StrEnum):
    """Where on a piece a stroke lands. Code order is the wire order; append only."""

    HEAD = "head"
    RIM = "rim"
    CROSS_STICK = "cross_stick"
    BOW = "bow"
    EDGE = "edge"
    BELL = "bell"
    PEDAL = "pedal"

    @property
    def code(self) -> int:
        return ZONES.index(self)


ZONES: tuple[Zone, ...] = tuple(Zone)

#: Zones a piece of each kind offers when its kit file does not list them.
DEFAULT_ZONES: dict[PieceKind, tuple[Zone, ...]] = {
    PieceKind.KICK: (Zone.HEAD,),
    PieceKind.SNARE: (Zone.HEAD, Zone.RIM, Zone.CROSS_STICK),
    PieceKind.TOM: (Zone.HEAD, Zone.RIM),
    PieceKind.HIHAT: (Zone.BOW, Zone.EDGE, Zone.PEDAL),
    PieceKind.CRASH: (Zone.BOW, Zone.EDGE, Zone.BELL),
    PieceKind.RIDE: (Zone.BOW, Zone.EDGE, Zone.BELL),
    PieceKind.SPLASH: (Zone.BOW, Zone.EDGE, Zone.BELL),
    PieceKind.CHINA: (Zone.BOW, Zone.EDGE, Zone.BELL),
    PieceKind.COWBELL: (Zone.HEAD,),
    PieceKind.TAMBOURINE: (Zone.HEAD,),
    PieceKind.PERCUSSION: (Zone.HEAD,),
}


class HiHat(StrEnum):
    """The hi-hat articulation a note names (its pedal position may refine it via CC4)."""

    NONE = "none"  # not a hi-hat note
    CLOSED = "closed"
    HALF = "half"
    OPEN = "open"
    PEDAL = "pedal"

    @property
    def code(self) -> int:
        return HIHATS.index(self)

    @property
    def nominal_openness(self) -> float:
        """Openness (0 closed … 1 open) implied by the note alone, used before any CC4."""
        return {HiHat.OPEN: 1.0, HiHat.HALF: 0.5}.get(self, 0.0)


HIHATS: tuple[HiHat, ...] = tuple(HiHat)


class Limb(StrEnum):
    """A playing limb. Hands strike with sticks, feet with pedals."""

    RH = "RH"
    LH = "LH"
    RF = "RF"
    LF = "LF"

    @property
    def is_hand(self) -> bool:
        return self in (Limb.RH, Limb.LH)

    @property
    def mirrored(self) -> Limb:
        return _MIRROR[self]


_MIRROR = {Limb.RH: Limb.LH, Limb.LH: Limb.RH, Limb.RF: Limb.LF, Limb.LF: Limb.RF}
