"""Beat-tracking benchmark: the online tracker on GMD grooves played as if live.

For ``--files`` grooves in 4/4 of the Groove MIDI Dataset (``--groove DIR``; CC BY 4.0), picked
with a fixed seed, the onsets are fed to :func:`livedrummer.live.beat.track_beats` (the online
tracker's offline twin: the beats it predicts before each next onset arrives), and the beats
are compared with the file's own tempo map: the fraction of reference beats after the first
four bars with a detected beat within +-70 ms. Prints the median and mean over the grooves,
the share of grooves at or above 90 %, and how many had their tempo within 4 % at the end.
"""

from __future__ import annotations

import argparse
import random
import statistics
import time
from pathlib import Path

import numpy as np

from livedrummer.live.beat import BeatTracker, beat_accuracy, onset_weights, track_beats
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parents[2]
    p = argparse.ArgumentParser(prog="livedrummer bench beats")
    p.add_argument("--groove", type=Path, default=here.parent / "shared" / "data" / "groove")
    p.add_argument("--files", type=int, default=40)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    files = sorted(args.groove.rglob("*beat_4-4.mid"))
    if not files:
        print(f"bench beats: no GMD grooves under {args.groove}")
        return 1
    random.Random(args.seed).shuffle(files)
    note_map = load_note_map("roland-td")
    accs: list[float] = []
    tempo_ok = 0
    started = time.perf_counter()
    onsets = 0
    for path in files[: args.files]:
        perf = read_midi_file(path, note_map)
        on, grid = perf.onsets, perf.grid
        bars = grid.beat_s[grid.beat_in_bar == 0]
        if on.size < 20 or bars.size < 6:
            continue
        times, weights = on["time_s"].astype(np.float64), onset_weights(on)
        detected = track_beats(times, weights, perf.duration_s)
        reference = grid.beat_s[grid.beat_s <= perf.duration_s]
        accs.append(beat_accuracy(detected, reference, float(bars[4])))
        tracker = BeatTracker()
        for t, w in zip(times, weights, strict=True):
            tracker.process(float(t), float(w))
        ref_bpm = 60.0 / float(np.median(np.diff(reference)))
        tempo_ok += int(tracker.bpm is not None and abs(tracker.bpm / ref_bpm - 1) < 0.04)
        onsets += on.size
    spent = time.perf_counter() - started
    print(f"beats on {len(accs)} GMD 4/4 grooves (seed {args.seed}): reference beats matched "
          f"within +-70 ms after the first four bars: median {100 * statistics.median(accs):.1f} %,"
          f" mean {100 * float(np.mean(accs)):.1f} %; grooves at >= 90 %: "
          f"{100 * float(np.mean(np.array(accs) >= 0.9)):.0f} %; tempo within 4 % at the end: "
          f"{tempo_ok}/{len(accs)}; {1e6 * spent / max(onsets, 1) / 2:.0f} us per onset"
          )  # fmt: skip
    return 0
