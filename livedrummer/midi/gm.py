"""The General MIDI percussion note that sounds a stroke: one rule for every GM sampler.

Why this shape. The SoundFont and SFZ renderers, their live mixers and ``input --thru`` with
``--thru-map general-midi`` all send General MIDI notes to a sampler, and a stroke must sound
the same whichever path it takes; so the choice is made here, once, from the bundled
``general-midi`` note map (read once and kept), and the audio modules and the thru re-mapping
import it (the audio package sits above ``midi`` in the package order).

The rule (:func:`gm_note`): the onset's own note when General MIDI means the same
instrument, zone and hi-hat articulation by it (so a GM file keeps its 35-vs-36 kicks,
electric snares and Latin percussion); otherwise, as for an e-kit's notes (a Roland TD sends
22 for a closed hi-hat edge and 48 for its first tom), the GM note of the onset's instrument and
zone, taken from the ``general-midi`` map (lowest note when several fit), falling back to the
instrument's note in any zone (cymbal edges sound as bows, tom rims as heads) and a half-open
hi-hat to the open one (46). One choice differs from inverting the map: a snare rim shot sounds
as the acoustic snare (38), not as the hand clap (39) that the map files under rim.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone
from livedrummer.midi.notemap import load_note_map

_SNARE_RIM_NOTE = 38  # GM has no rim shot; 39 is a hand clap

GmKey = tuple[str, Zone, HiHat]


def warm_note_tables() -> None:
    """Read the bundled General MIDI map that :func:`gm_note` uses now (it is read once and
    kept): a live mixer calls this when it is made, so its first stroke is not late."""
    _gm_tables()


@cache
def _gm_tables() -> tuple[dict[int, GmKey], dict[GmKey, int], dict[str, int]]:
    gm = load_note_map("general-midi")
    meaning = {n: (s.instrument, s.zone, s.hihat) for n, s in gm.notes.items()}
    exact: dict[GmKey, int] = {}
    anyzone: dict[str, int] = {}
    for note in sorted(meaning):
        exact.setdefault(meaning[note], note)
        anyzone.setdefault(meaning[note][0], note)
    exact[("snare", Zone.RIM, HiHat.NONE)] = _SNARE_RIM_NOTE
    return meaning, exact, anyzone


def gm_note(note: int, instrument: str, zone: Zone, hihat: HiHat) -> int:
    """The General MIDI percussion note that sounds this stroke (see the module docstring)."""
    meaning, exact, anyzone = _gm_tables()
    key = (instrument, zone, hihat)
    if meaning.get(note) == key:
        return note
    if key in exact:
        return exact[key]
    if instrument == "hihat":
        wanted = HiHat.OPEN if hihat is HiHat.HALF else hihat
        for (name, _zone, art), gm in sorted(exact.items(), key=lambda kv: kv[1]):
            if name == "hihat" and art is wanted:
                return gm
    return anyzone[instrument]


def gm_notes(onsets: np.ndarray) -> np.ndarray:
    """:func:`gm_note` of every onset (uint8)."""
    out = np.zeros(len(onsets), np.uint8)
    for i, o in enumerate(onsets):
        piece, zone = INSTRUMENTS[int(o["instrument"])], ZONES[int(o["zone"])]
        out[i] = gm_note(int(o["note"]), piece, zone, HIHATS[int(o["hihat"])])
    return out
