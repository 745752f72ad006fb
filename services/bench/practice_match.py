"""``livedrummer bench practice_match``: how long judging a take takes.

Two figures, medians of ``--repeat`` runs: the monotone matcher alone
(:func:`livedrummer.practice.match.monotone_match`) on ``--notes`` notes of one piece 75 ms apart
(16ths at 200 bpm: every note has two neighbours inside the ±100 ms window, the worst case for
the banded programme) played with 12 ms of timing noise; and the whole judgement (all pieces,
wrong piece, extra, then the graded summary) of a long Groove MIDI Dataset performance (the
largest of its first 200 files) against itself with the same noise (``--corpus DIR``, default
``../shared/data/groove`` beside the checkout; skipped when absent). Both should stay far below
a pass's length: the live rig judges each pass between two notes.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.practice.grade import summary
from livedrummer.practice.match import match_take, monotone_match

from ._paths import DEFAULT_CORPUS


def _median_s(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench practice_match")
    parser.add_argument("--notes", type=int, default=10_000, help="notes (default 10000)")
    parser.add_argument("--repeat", type=int, default=5, help="runs per figure (default 5)")
    parser.add_argument("--corpus", type=Path, help="Groove MIDI Dataset folder")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(1)
    ref = np.arange(args.notes) * 0.075
    played = np.sort(ref + rng.normal(0.0, 0.012, ref.size))
    dense = _median_s(lambda: monotone_match(ref, played, 0.1), args.repeat)
    print(
        f"monotone matcher, {args.notes} notes 75 ms apart (window ±100 ms): "
        f"{dense * 1e3:.1f} ms ({args.notes / dense:,.0f} notes/s)"
    )
    corpus = args.corpus or DEFAULT_CORPUS
    files = sorted(corpus.rglob("*.mid")) if corpus.is_dir() else []
    if not files:
        print("whole judgement: skipped (no Groove MIDI Dataset; --corpus DIR)")
        return 0
    note_map = load_note_map("roland-td")
    longest = max(files[:200], key=lambda p: p.stat().st_size)
    onsets = read_midi_file(longest, note_map).onsets
    take = onsets.copy()
    take["time_s"] += rng.normal(0.0, 0.012, take.size)
    take = take[np.argsort(take["time_s"])]
    whole = _median_s(lambda: summary(match_take(onsets, take)), args.repeat)
    print(
        f"whole judgement with summary, {longest.name} ({onsets.size} notes): {whole * 1e3:.1f} ms"
    )
    return 0
