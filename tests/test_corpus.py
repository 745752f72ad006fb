"""The whole Groove MIDI Dataset through the Roland map, checked against an independent count.

The independent count reads raw mido messages itself (no livedrummer code): note-ons with
velocity > 0 per note, exact doubles (same tick, channel, note, velocity) and polyphonic
aftertouch. Every file must ingest with no unknown note, the same per-note totals, openness
on every hi-hat onset, and the drummer6 chokes found.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import mido
import numpy as np

from livedrummer.kit.vocabulary import HIHATS, HiHat
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.events import ControlKind


def independent_count(path: Path) -> tuple[Counter[int], int, int]:
    notes: Counter[int] = Counter()
    doubles = 0
    polytouch = 0
    seen: set[tuple[int, int, int, int]] = set()
    tick = 0
    for msg in mido.merge_tracks(mido.MidiFile(path).tracks):
        tick += msg.time
        if msg.type == "note_on" and msg.velocity > 0:
            notes[msg.note] += 1
            key = (tick, msg.channel, msg.note, msg.velocity)
            doubles += key in seen
            seen.add(key)
        elif msg.type == "polytouch":
            polytouch += 1
    return notes, doubles, polytouch


def test_every_groove_file_ingests_exactly(groove_files: list[Path]) -> None:
    assert len(groove_files) == 1150
    td = load_note_map("roland-td")
    totals: Counter[int] = Counter()
    onsets = 0
    chokes_by_drummer: Counter[str] = Counter()
    raw_polytouch_by_drummer: Counter[str] = Counter()
    for path in groove_files:
        perf = read_midi_file(path, td)
        notes, doubles, polytouch = independent_count(path)
        drummer = path.relative_to(path.parents[2]).parts[0]
        assert perf.stats.unknown_notes == Counter(), path
        assert perf.stats.note_ons == notes, path
        assert perf.stats.duplicates_removed == doubles, path
        assert perf.onsets.size == sum(notes.values()) - doubles, path
        summary = perf.summary()
        assert summary["by_note"] == {str(k): v for k, v in sorted(notes.items())}
        hihat = perf.onsets["hihat"] != HIHATS.index(HiHat.NONE)
        assert not np.isnan(perf.onsets["openness"][hihat]).any(), path
        assert np.isnan(perf.onsets["openness"][~hihat]).all(), path
        assert np.all(np.diff(perf.onsets["time_s"]) >= 0), path
        chokes_by_drummer[drummer] += int(np.sum(perf.controls["kind"] == ControlKind.CHOKE))
        raw_polytouch_by_drummer[drummer] += polytouch
        totals.update(notes)
        onsets += perf.onsets.size
    assert chokes_by_drummer == raw_polytouch_by_drummer
    assert chokes_by_drummer["drummer6"] > 0
    assert onsets == sum(totals.values()) - 2  # the corpus holds exactly two doubles
