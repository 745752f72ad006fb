"""Drum tab with sticking: the way a teacher writes a pattern and its limbs, as plain text.

The annotated corpus (``tests/data/sticking/*.tab``) is written in this format, and a user can
write one to test a kit. One row per instrument, one column per grid step, each cell the limb
that plays that note::

    # 8th-note rock groove
    kit rock5          # optional: the kit the sticking is meant for (default rock5)
    tempo 100          # quarter notes per minute
    steps 2            # grid steps per beat: 2 = eighths, 4 = sixteenths, 3 = triplets
    hihat   R R R R R R R R | R R R R R R R R
    snare   . . L . . . L . | . . L . . . L .
    kick    RF . . . RF RF . . | RF . . . RF . . .

Cells: ``.`` no note; ``R``/``L`` a hand (``r``/``l``: a ghost note, played softly);
``RF``/``LF`` a foot (``LF`` on a hi-hat row: played with the pedal); ``X`` a note the teacher
would leave out. ``|`` is a bar line and ignored. A row is named by an instrument role
(:data:`~livedrummer.kit.vocabulary.INSTRUMENTS`), optionally ``:zone`` (``snare:rim``,
``ride:bell``, ``hihat:pedal``) or ``hihat:open``. Rows must all have the same number of cells.
Notes get General MIDI note numbers, for display only.

Limits: one tempo and one grid per file; no dynamics beyond ghost notes; no flams.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.kit.vocabulary import (
    DEFAULT_ZONES,
    HIHATS,
    INSTRUMENT_CODE,
    ZONES,
    HiHat,
    Limb,
    PieceKind,
    Zone,
)
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED
from livedrummer.timeline.events import ONSET_DTYPE


class ScoreError(LivedrummerError):
    """A sticking score or tab file is malformed."""


_CELLS = {
    "R": (Limb.RH, 100),
    "L": (Limb.LH, 100),
    "r": (Limb.RH, 40),
    "l": (Limb.LH, 40),
    "RF": (Limb.RF, 100),
    "LF": (Limb.LF, 100),
}
_GM_NOTE = {
    "kick": 36,
    "snare": 38,
    "hihat": 42,
    "tom1": 50,
    "tom2": 48,
    "tom3": 47,
    "tom4": 45,
    "tom5": 43,
    "tom6": 41,
    "crash1": 49,
    "crash2": 57,
    "ride": 51,
    "splash": 55,
    "china": 52,
    "cowbell": 56,
    "tambourine": 54,
    "percussion": 60,
}
_KIND_OF = {
    "kick": PieceKind.KICK,
    "snare": PieceKind.SNARE,
    "hihat": PieceKind.HIHAT,
    "crash1": PieceKind.CRASH,
    "crash2": PieceKind.CRASH,
    "ride": PieceKind.RIDE,
    "splash": PieceKind.SPLASH,
    "china": PieceKind.CHINA,
}


@dataclass(frozen=True)
class Tab:
    """A parsed tab: onsets in time order, the teacher's limbs, and the beat grid."""

    name: str
    kit: str
    onsets: np.ndarray  # ONSET_DTYPE
    limbs: np.ndarray  # int8, LIMBS index or NOT_PLAYED for an X
    beat_s: np.ndarray


def read_tab(path: Path) -> Tab:
    return parse_tab(path.read_text(encoding="utf-8"), str(path))


def _row_spec(name: str, where: str) -> tuple[int, int, int, int]:
    """(instrument code, zone code, hihat code, note) of a row name."""
    inst, _, zone_name = name.partition(":")
    if inst not in INSTRUMENT_CODE:
        raise ScoreError(f"{where}: unknown instrument {inst!r}")
    kind = _KIND_OF.get(inst, PieceKind.TOM if inst.startswith("tom") else PieceKind.PERCUSSION)
    hihat = HiHat.CLOSED if inst == "hihat" else HiHat.NONE
    note = _GM_NOTE[inst]
    zone = DEFAULT_ZONES[kind][0]
    if zone_name == "open" and inst == "hihat":
        hihat, note = HiHat.OPEN, 46
    elif zone_name == "pedal" and inst == "hihat":
        zone, hihat, note = Zone.PEDAL, HiHat.PEDAL, 44
    elif zone_name:
        try:
            zone = Zone(zone_name)
        except ValueError:
            raise ScoreError(f"{where}: unknown zone {zone_name!r}") from None
        note = 53 if (inst, zone) == ("ride", Zone.BELL) else note
    return INSTRUMENT_CODE[inst], ZONES.index(zone), HIHATS.index(hihat), note


def parse_tab(text: str, source: str = "<tab>") -> Tab:
    kit, tempo, steps = "rock5", 120.0, 4
    rows: list[tuple[str, list[str], int]] = []
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        key, *rest = line.split()
        try:
            if key == "kit":
                kit = rest[0]
            elif key == "tempo":
                tempo = float(rest[0])
            elif key == "steps":
                steps = int(rest[0])
            else:
                rows.append((key, [c for c in rest if c != "|"], lineno))
        except (IndexError, ValueError):
            raise ScoreError(f"{source}:{lineno}: bad {key!r} line: {raw.strip()!r}") from None
    if not rows:
        raise ScoreError(f"{source}: no instrument rows")
    width = len(rows[0][1])
    step_s = 60.0 / tempo / steps
    found: list[tuple[int, int, tuple[int, int, int, int], int, int]] = []
    for order, (name, cells, lineno) in enumerate(rows):
        where = f"{source}:{lineno}"
        if len(cells) != width:
            raise ScoreError(f"{where}: {len(cells)} cells, the first row has {width}")
        spec = _row_spec(name, where)
        for col, cell in enumerate(cells):
            if cell == ".":
                continue
            if cell == "X":
                limb, vel = NOT_PLAYED, 100
            elif cell in _CELLS:
                lb, vel = _CELLS[cell]
                limb = LIMB_CODE[lb]
            else:
                raise ScoreError(f"{where}: cell {col + 1} is {cell!r}, not R L r l RF LF X .")
            found.append((col, order, spec, limb, vel))
    found.sort(key=lambda f: (f[0], f[1]))
    on = np.zeros(len(found), dtype=ONSET_DTYPE)
    limbs = np.array([f[3] for f in found], dtype=np.int8)
    for i, (col, _, (inst, zone, hihat, note), _, vel) in enumerate(found):
        on[i] = (col * step_s, note, vel, 9, inst, zone, hihat, np.nan, 0)
        if HIHATS[hihat] is not HiHat.NONE:
            on["openness"][i] = HIHATS[hihat].nominal_openness
    beats = int(np.ceil(width / steps)) + 1
    return Tab(Path(source).stem, kit, on, limbs, np.arange(beats) * 60.0 / tempo)
