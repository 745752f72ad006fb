"""Shared builders for the sticking tests (no tests here): onsets from (time, instrument) tuples."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Zone
from livedrummer.timeline.events import ONSET_DTYPE

DATA = Path(__file__).parents[2] / "data" / "sticking"
TABS = sorted(DATA.glob("*.tab"))
GMD = Path(__file__).resolve().parents[3].parent / "shared" / "data" / "groove"
DEMO = Path(__file__).resolve().parents[3] / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


def onsets(*notes: tuple[float, str] | tuple[float, str, int]) -> np.ndarray:
    """Onsets from (time_s, instrument[:zone], velocity=100) tuples, sorted by time."""
    out = np.zeros(len(notes), dtype=ONSET_DTYPE)
    for i, note in enumerate(sorted(notes, key=lambda n: n[0])):
        t, name = note[0], note[1]
        vel = note[2] if len(note) > 2 else 100  # type: ignore[misc]
        inst, _, zone = name.partition(":")
        hihat = HiHat.NONE
        if inst == "hihat":
            hihat = HiHat.PEDAL if zone == "pedal" else HiHat.CLOSED
        z = (
            Zone(zone)
            if zone
            else (
                Zone.BOW if inst in ("hihat", "ride", "crash1", "crash2", "splash") else Zone.HEAD
            )
        )
        out[i] = (
            t,
            0,
            vel,
            9,
            INSTRUMENT_CODE[inst],
            ZONES.index(z),
            HIHATS.index(hihat),
            np.nan,
            0,
        )
    return out
