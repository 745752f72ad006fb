"""The whole Groove MIDI Dataset through the Roland map, checked against an independent count.

The independent count reads raw mido messages itself (no livedrummer code): note-ons with
velocity > 0 per note, doubled notes (the same note again within 1 ms, in seconds from the
file's own tempo changes, as :func:`livedrummer.midi.decode.merge_doubled_notes` defines them)
and polyphonic aftertouch. Every file must ingest with no unknown note, the same per-note
totals, openness on every hi-hat onset, and the drummer6 chokes found.

The files are spread over ``os.cpu_count()`` worker processes; each worker reads a file both
ways and sends back the facts compared here, so every assertion is made in this process.
"""

from __future__ import annotations

import bisect
import itertools
import os
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import mido
import numpy as np

from livedrummer.kit.vocabulary import HIHATS, HiHat
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.events import ControlKind

DOUBLE_WINDOW_S = 0.001


def independent_count(path: Path) -> tuple[Counter[int], int, int, int]:
    """Note-ons per note, doubled notes, exact doubles (same tick, channel, note and velocity)
    and polyphonic aftertouch, from mido's messages."""
    mid = mido.MidiFile(path)
    tempos: list[tuple[int, int]] = []
    notes: list[tuple[int, int]] = []  # (absolute tick, note)
    polytouch = 0
    seen: set[tuple[int, int, int, int]] = set()
    exact = 0
    for track in mid.tracks:
        tick = 0
        for msg in track:
            tick += msg.time
            if msg.type == "note_on" and msg.velocity > 0:
                notes.append((tick, msg.note))
                key = (tick, msg.channel, msg.note, msg.velocity)
                exact += key in seen
                seen.add(key)
            elif msg.type == "set_tempo":
                tempos.append((tick, msg.tempo))
            elif msg.type == "polytouch":
                polytouch += 1
    # Seconds from the tempo changes (120 bpm until the first), segment by segment.
    tempos.sort(key=lambda t: t[0])
    starts, base_s, rates = [0], [0.0], [500_000]
    for tick, tempo in tempos:
        base_s.append(base_s[-1] + (tick - starts[-1]) * rates[-1] / (mid.ticks_per_beat * 1e6))
        starts.append(tick)
        rates.append(tempo)
    by_note: dict[int, list[float]] = {}
    for tick, note in notes:
        k = bisect.bisect_right(starts, tick) - 1
        seconds = base_s[k] + (tick - starts[k]) * rates[k] / (mid.ticks_per_beat * 1e6)
        by_note.setdefault(note, []).append(seconds)
    doubles = 0
    for times in by_note.values():
        times.sort()
        doubles += sum(b - a <= DOUBLE_WINDOW_S + 1e-9 for a, b in itertools.pairwise(times))
    return Counter({n: len(t) for n, t in by_note.items()}), doubles, exact, polytouch


@dataclass(frozen=True)
class Facts:
    """What one file gave, read by livedrummer and counted independently."""

    path: Path
    unknown: Counter[int]
    note_ons: Counter[int]
    duplicates_removed: int
    onsets: int
    by_note: dict[str, int]
    hihat_openness_set: bool
    other_openness_nan: bool
    sorted_in_time: bool
    chokes: int
    notes: Counter[int]
    doubles: int
    exact_doubles: int
    polytouch: int


def facts(path: Path) -> Facts:
    perf = read_midi_file(path, load_note_map("roland-td"))
    notes, doubles, exact, polytouch = independent_count(path)
    hihat = perf.onsets["hihat"] != HIHATS.index(HiHat.NONE)
    return Facts(
        path=path,
        unknown=perf.stats.unknown_notes,
        note_ons=perf.stats.note_ons,
        duplicates_removed=perf.stats.duplicates_removed,
        onsets=int(perf.onsets.size),
        by_note=perf.summary()["by_note"],
        hihat_openness_set=not np.isnan(perf.onsets["openness"][hihat]).any(),
        other_openness_nan=bool(np.isnan(perf.onsets["openness"][~hihat]).all()),
        sorted_in_time=bool(np.all(np.diff(perf.onsets["time_s"]) >= 0)),
        chokes=int(np.sum(perf.controls["kind"] == ControlKind.CHOKE)),
        notes=notes,
        doubles=doubles,
        exact_doubles=exact,
        polytouch=polytouch,
    )


def test_every_groove_file_ingests_exactly(groove_files: list[Path]) -> None:
    assert len(groove_files) == 1150
    totals: Counter[int] = Counter()
    onsets = 0
    doubles = exact = 0
    chokes_by_drummer: Counter[str] = Counter()
    raw_polytouch_by_drummer: Counter[str] = Counter()
    workers = os.cpu_count() or 1
    with ProcessPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(facts, groove_files, chunksize=16))
    assert [f.path for f in results] == groove_files
    for f in results:
        path = f.path
        drummer = path.relative_to(path.parents[2]).parts[0]
        assert f.unknown == Counter(), path
        assert f.note_ons == f.notes, path
        assert f.duplicates_removed == f.doubles, path
        assert f.onsets == sum(f.notes.values()) - f.doubles, path
        assert f.by_note == {str(k): v for k, v in sorted(f.notes.items())}, path
        assert f.hihat_openness_set, path
        assert f.other_openness_nan, path
        assert f.sorted_in_time, path
        chokes_by_drummer[drummer] += f.chokes
        raw_polytouch_by_drummer[drummer] += f.polytouch
        totals.update(f.notes)
        onsets += f.onsets
        doubles += f.doubles
        exact += f.exact_doubles
    assert chokes_by_drummer == raw_polytouch_by_drummer
    assert chokes_by_drummer["drummer6"] > 0
    assert onsets == sum(totals.values()) - doubles
    # The corpus holds exactly two exact doubles (same tick and velocity) and 18 more pairs of
    # one note within 1 ms at two velocities (in three files), each one hit.
    assert exact == 2 and doubles == 20
