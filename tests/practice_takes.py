"""Takes with planted mistakes, made from a Groove MIDI Dataset reference (tests only).

Offsets from a known distribution; deleted notes; moved notes (to a piece with no reference
note near); extra notes far from any reference note. The planted notes are spaced so the truth
is unambiguous: every deleted or moved note is ≥ 0.5 s from every other planted one, and each
extra lies ≥ 0.3 s from every reference note.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.kit.vocabulary import INSTRUMENT_CODE, INSTRUMENTS
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from services.practice.take import write_take

MAP = "roland-td"
_MOVE_TO = ("tom1", "tom2", "tom3", "crash1", "ride", "snare", "kick")


@dataclass(frozen=True)
class Planted:
    reference_notes: int
    hits: int
    missed: int
    wrong_piece: int
    extra: int
    mean_offset_ms: float


def note_for(piece: str) -> int:
    spec = next(
        s
        for s in load_note_map(MAP).notes.values()
        if s.instrument == piece and s.zone.value in ("head", "bow")
    )
    return spec.note


def plant_take(
    reference: Path,
    out: Path,
    seed: int = 1,
    deleted: int = 7,
    moved: int = 5,
    extra: int = 4,
    mean_ms: float = 6.0,
    sd_ms: float = 9.0,
    limit_s: float | None = None,
) -> Planted:
    rng = np.random.default_rng(seed)
    ref = read_midi_file(reference, load_note_map(MAP)).onsets
    if limit_s is not None:
        ref = ref[ref["time_s"] < limit_s]
    times = ref["time_s"]
    chosen: list[int] = []
    for i in rng.permutation(ref.size).tolist():
        if len(chosen) == deleted + moved:
            break
        if all(abs(times[i] - times[j]) >= 0.5 for j in chosen):
            chosen.append(i)
    gone, move = chosen[:deleted], []
    for i in chosen[deleted:]:
        here = INSTRUMENTS[int(ref["instrument"][i])]
        for piece in rng.permutation(_MOVE_TO).tolist():
            same = ref["instrument"] == INSTRUMENT_CODE[piece]
            if piece != here and not np.any(same & (np.abs(times - times[i]) < 0.3)):
                move.append((i, piece))
                break
    assert len(move) == moved, "could not move every chosen note"
    offsets = np.clip(rng.normal(mean_ms, sd_ms, ref.size), -30.0, 30.0)
    take = ref.copy()
    take["time_s"] = times + offsets / 1e3
    for i, piece in move:
        take["note"][i] = note_for(piece)
        take["instrument"][i] = INSTRUMENT_CODE[piece]
    keep = np.ones(ref.size, dtype=bool)
    keep[gone] = False
    hit = keep.copy()
    hit[[i for i, _ in move]] = False
    end = float(times.max())
    extras = take[:extra].copy()
    extras["time_s"] = end + 1.0 + np.arange(extra) * 0.7
    gaps = np.flatnonzero(np.diff(times) > 0.7)
    for k, g in enumerate(gaps[: extra // 2].tolist()):
        extras["time_s"][k] = (times[g] + times[g + 1]) / 2
    take = np.concatenate([take[keep], extras])
    write_take(out, take)
    return Planted(
        reference_notes=int(ref.size),
        hits=int(hit.sum()),
        missed=deleted,
        wrong_piece=moved,
        extra=extra,
        mean_offset_ms=float(offsets[hit].mean()),
    )
