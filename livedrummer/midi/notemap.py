"""Note maps: which instrument and zone each MIDI note number means on a given module.

E-kit modules disagree about note numbers (a Roland TD sends 22 for a closed hi-hat edge, a
General MIDI file uses 42 for any closed hi-hat, a Yamaha DTXplorer sends 31 for its snare), so
the map is data, chosen by name like a kit. A map also says which controller carries the
hi-hat pedal position and which value means fully closed (a TD-11 tops out near 90, not 127),
so openness is comparable across modules.

File layout (strict, like kits)::

    [map]
    name = "roland-td"            # must equal the file name
    description = "..."
    sources = ["...", "..."]      # where the numbers come from (``kits`` lists them)
    hihat_cc = 4
    hihat_cc_closed = 90

    [notes]
    46 = { piece = "hihat", zone = "bow", hihat = "open", label = "Hi-hat open bow" }
    33 = { ignored = true, label = "Metronome click" }

``chart = true`` in ``[map]`` marks a rhythm-game chart's map: a file read with it is read as a
chart (:mod:`livedrummer.midi.chart`), and ``auto`` never picks it by counting notes.

A note marked ``ignored`` is a sound with no place on a drum kit (a metronome click, a scratch):
it is known (the ``auto`` map choice counts it), never turned into an onset, and counted and
reported by the decoder as ignored rather than unknown.

Choosing among the bundled maps (``auto``) counts, for each map, how many of a file's notes it
knows; the most wins. Drum plugins' maps (EZdrummer, Superior Drummer) name nearly every note
0-127, so they know every note of most files and tie with the map the file was written for.
Ties go to the map met first in :func:`bundled_note_maps`' order: ``general-midi``, then the
smaller tables before the larger (a file that fits a module's 26 notes is more likely that
module's than a plugin's with 125), then by name; and the line that reports the choice names
the maps tied with it (:func:`livedrummer.midi.smf.choose_map`). A map that names every note
would also win any General MIDI file with one stray note, and read its congas as hi-hats; so
``general-midi`` is kept unless a map with a larger table knows more than 1 % of the file's
notes more.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from types import MappingProxyType

from livedrummer.config import Table, read_toml
from livedrummer.errors import NoteMapError
from livedrummer.kit.catalog import entries, looks_like_path
from livedrummer.kit.vocabulary import (
    DEFAULT_ZONES,
    INSTRUMENT_CODE,
    INSTRUMENTS,
    HiHat,
    PieceKind,
    Zone,
)

_CYMBAL_ZONES = ("bow", "edge", "bell")
_DRUM_ZONES = ("head", "rim", "cross_stick")
_HIHAT_ZONES = ("bow", "edge", "bell", "pedal")


@dataclass(frozen=True, slots=True)
class NoteSpec:
    """What one note number means."""

    note: int
    instrument: str
    zone: Zone
    hihat: HiHat
    label: str

    @property
    def instrument_code(self) -> int:
        return INSTRUMENT_CODE[self.instrument]


@dataclass(frozen=True)
class NoteMap:
    """A module's note numbering, plus its hi-hat controller calibration."""

    name: str
    description: str
    hihat_cc: int
    hihat_cc_closed: int
    notes: Mapping[int, NoteSpec]
    source: str = "<memory>"
    ignored: Mapping[int, str] = field(default_factory=dict)  # note -> label: never played
    chart: bool = False  # a rhythm-game chart's map (see livedrummer.midi.chart)
    sources: tuple[str, ...] = ()  # where the numbers come from, as the file cites them

    def __post_init__(self) -> None:
        object.__setattr__(self, "notes", MappingProxyType(dict(self.notes)))
        object.__setattr__(self, "ignored", MappingProxyType(dict(self.ignored)))

    def lookup(self, note: int) -> NoteSpec | None:
        return self.notes.get(note)

    @property
    def size(self) -> int:
        """How many notes the map names (played or ignored)."""
        return len(self.notes) + len(self.ignored)

    def knows(self, note: int) -> bool:
        """Whether the map says what ``note`` is (played or ignored)."""
        return note in self.notes or note in self.ignored

    def openness(self, cc_value: int) -> float:
        """Hi-hat openness 0 (closed) … 1 (open) from the pedal controller's value."""
        return min(1.0, max(0.0, 1.0 - cc_value / self.hihat_cc_closed))


def parse_note_map(data: dict[str, object], source: str, stem: str | None = None) -> NoteMap:
    """Build a :class:`NoteMap` from parsed TOML, checking every key and value."""
    root = Table(data, source, "", NoteMapError)
    head = root.table("map")
    name = head.text("name")
    if stem is not None and name != stem:
        raise head.fail("name", f"must equal the file name {stem!r}", name)
    description = head.text("description", "")
    hihat_cc = head.integer("hihat_cc", 4, lo=0, hi=127)
    closed = head.integer("hihat_cc_closed", 127, lo=1, hi=127)
    chart = head.boolean("chart", False)
    sources = tuple(head.texts("sources", []))
    head.done()
    table = root.table("notes")
    notes = {}
    ignored = {}
    for key in table.keys():
        if not key.isdigit() or not 0 <= int(key) <= 127:
            raise table.fail(key, "note keys must be MIDI note numbers 0-127")
        entry = table.table(key)
        if entry.boolean("ignored", False):
            ignored[int(key)] = entry.text("label")
            entry.done()
        else:
            notes[int(key)] = _parse_note(int(key), entry)
    table.done()
    root.done()
    return NoteMap(name, description, hihat_cc, closed, notes, source, ignored, chart, sources)


def _parse_note(note: int, t: Table) -> NoteSpec:
    instrument = t.text("piece", choices=INSTRUMENTS)
    zone = t.text("zone", choices=[z.value for z in Zone])
    allowed = _allowed_zones(instrument)
    if zone not in allowed:
        raise t.fail("zone", f"{instrument} has zones {', '.join(allowed)}", zone)
    if instrument == "hihat":
        hihat = HiHat(t.text("hihat", choices=[h.value for h in HiHat if h is not HiHat.NONE]))
        if (hihat is HiHat.PEDAL) != (zone == "pedal"):
            raise t.fail("hihat", "the pedal articulation goes with zone 'pedal'", hihat.value)
    else:
        hihat = HiHat.NONE
    spec = NoteSpec(note, instrument, Zone(zone), hihat, t.text("label"))
    t.done()
    return spec


def _allowed_zones(instrument: str) -> tuple[str, ...]:
    if instrument == "hihat":
        return _HIHAT_ZONES
    if instrument in ("crash1", "crash2", "ride", "splash", "china"):
        return _CYMBAL_ZONES
    if instrument in ("cowbell", "tambourine", "percussion", "kick"):
        return tuple(z.value for z in DEFAULT_ZONES[PieceKind(instrument)])
    return _DRUM_ZONES


def load_note_map_file(path: Path) -> NoteMap:
    return parse_note_map(read_toml(path, NoteMapError), str(path), path.stem)


def load_note_map(spec: str) -> NoteMap:
    """A note map by path or name."""
    if looks_like_path(spec):
        return load_note_map_file(Path(spec))
    found = entries("kits/maps")
    if spec not in found:
        known = ", ".join(sorted(found)) or "(none)"
        raise NoteMapError(f"unknown note map {spec!r}; known maps: {known}")
    return load_note_map_file(found[spec].path)


def note_map_names() -> list[str]:
    return sorted(entries("kits/maps"))


#: The map name that asks the file reader to choose among :func:`bundled_note_maps`.
AUTO = "auto"
#: Preferred first when two bundled maps know as many of a file's notes.
_FIRST = "general-midi"


@cache
def bundled_note_maps() -> tuple[NoteMap, ...]:
    """Every note map shipped with livedrummer, in the order ``auto`` prefers them on a tie:
    ``general-midi`` first, then the smaller tables, then by name (the ``auto`` choice's
    candidates; a user's own maps are chosen by name). Read once per process (20 ms for the
    13 files; ``check DIR`` reads a folder of files with them): the maps are immutable and the
    package's files do not change while it runs."""
    from livedrummer.resources import data_dir

    maps = [load_note_map_file(p) for p in (data_dir("kits") / "maps").glob("*.toml")]
    return tuple(sorted(maps, key=lambda m: (m.name != _FIRST, m.size, m.name)))
