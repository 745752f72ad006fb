"""Ingest benchmark: read every Groove MIDI Dataset file with the Roland map.

Prints files, onsets, total seconds and onsets per second for the whole corpus, plus the
median per-file time over ``--repeat`` passes (default 1; the corpus pass itself is the figure).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file

from ._paths import DEFAULT_CORPUS, corpus


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench ingest")
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--map", default="roland-td")
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args(argv)
    files = sorted(corpus(args.corpus).rglob("*.mid"))
    note_map = load_note_map(args.map)
    totals = []
    for _ in range(args.repeat):
        onsets = 0
        per_file = []
        start = time.perf_counter()
        for f in files:
            t0 = time.perf_counter()
            onsets += read_midi_file(f, note_map).onsets.size
            per_file.append(time.perf_counter() - t0)
        totals.append(time.perf_counter() - start)
    total = statistics.median(totals)
    print(f"ingest: {len(files)} files, {onsets} onsets")
    print(f"  corpus time      {total:.2f} s (median of {args.repeat})")
    print(f"  onsets/s         {onsets / total:,.0f}")
    print(f"  per file median  {statistics.median(per_file) * 1e3:.2f} ms")
    return 0
