"""Beat-tracking benchmark: the online tracker on GMD grooves played as if live.

For ``--files`` grooves in 4/4 of the Groove MIDI Dataset (``--groove DIR``; CC BY 4.0), picked
with a fixed seed, the onsets are fed to :func:`livedrummer.live.beat.track_beats` (the online
tracker's offline twin: the beats it predicts before each next onset arrives), and the beats
are compared with the file's own tempo map: the fraction of reference beats after the first
four bars with a detected beat within +-70 ms. Prints the median and mean over the grooves,
the share of grooves at or above 90 %, and how many had their tempo within 4 % at the end;
then the precision (the fraction of detected beats in the same span with a reference beat
within +-70 ms: a tracker at double tempo matches every reference beat, and half of its own
beats are extra) and their F-measure, and the mean of each per groove family (GMD's style).
``--split test`` (or ``train``, ``validation``) takes the grooves from that part of GMD's own
split (``info.csv``): the tracker's constants were tuned on train and validation, so its
figure on unseen playing is the one on test.
"""

from __future__ import annotations

import argparse
import csv
import random
import statistics
import time
from pathlib import Path

import numpy as np

from livedrummer.live.beat import (
    BeatTracker,
    beat_accuracy,
    beat_precision,
    downbeat_weights,
    onset_weights,
    track_beats,
)
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parents[2]
    p = argparse.ArgumentParser(prog="livedrummer bench beats")
    p.add_argument("--groove", type=Path, default=here.parent / "shared" / "data" / "groove")
    p.add_argument("--files", type=int, default=40)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument(
        "--split",
        choices=("train", "validation", "test"),
        help="only grooves of this part of GMD's split (info.csv)",
    )
    args = p.parse_args(argv)
    files = sorted(args.groove.rglob("*beat_4-4.mid"))
    info: dict[str, dict[str, str]] = {}
    if (args.groove / "info.csv").exists():
        with (args.groove / "info.csv").open(newline="") as f:
            info = {r["midi_filename"]: r for r in csv.DictReader(f)}
    if args.split is not None:
        chosen = {k for k, r in info.items() if r["split"] == args.split}
        files = [f for f in files if f.relative_to(args.groove).as_posix() in chosen]
    if not files:
        print(f"bench beats: no GMD grooves under {args.groove}")
        return 1
    random.Random(args.seed).shuffle(files)
    note_map = load_note_map("roland-td")
    accs: list[float] = []
    precs: list[float] = []
    families: dict[str, list[tuple[float, float]]] = {}
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
        down = downbeat_weights(on)
        detected = track_beats(times, weights, perf.duration_s, downbeats=down)
        reference = grid.beat_s[grid.beat_s <= perf.duration_s]
        accs.append(beat_accuracy(detected, reference, float(bars[4])))
        precs.append(beat_precision(detected, reference, float(bars[4])))
        style = info.get(path.relative_to(args.groove).as_posix(), {}).get("style", "?")
        families.setdefault(style.split("/")[0], []).append((accs[-1], precs[-1]))
        tracker = BeatTracker()
        for t, w, d in zip(times, weights, down, strict=True):
            tracker.process(float(t), float(w), float(d))
        ref_bpm = 60.0 / float(np.median(np.diff(reference)))
        tempo_ok += int(tracker.bpm is not None and abs(tracker.bpm / ref_bpm - 1) < 0.04)
        onsets += on.size
    spent = time.perf_counter() - started
    part = "" if args.split is None else f", {args.split} split"
    print(
        f"beats on {len(accs)} GMD 4/4 grooves (seed {args.seed}{part}): reference beats matched "
        f"within +-70 ms after the first four bars: median {100 * statistics.median(accs):.1f} %,"
        f" mean {100 * float(np.mean(accs)):.1f} %; grooves at >= 90 %: "
        f"{100 * float(np.mean(np.array(accs) >= 0.9)):.0f} %; tempo within 4 % at the end: "
        f"{tempo_ok}/{len(accs)}; {1e6 * spent / max(onsets, 1) / 2:.0f} us per onset"
    )
    f1 = [_f(a, p) for a, p in zip(accs, precs, strict=True)]
    print(
        f"precision: mean {100 * float(np.mean(precs)):.1f} %; F-measure: median "
        f"{100 * statistics.median(f1):.1f} %, "
        f"mean {100 * float(np.mean(f1)):.1f} %"
    )
    print(
        "by family (grooves: matched mean, F mean): "
        + "; ".join(
            f"{name} ({len(v)}: {100 * np.mean([a for a, _ in v]):.1f}, "
            f"{100 * np.mean([_f(a, p) for a, p in v]):.1f})"
            for name, v in sorted(families.items())
        )
    )
    return 0


def _f(recall: float, precision: float) -> float:
    return 2 * recall * precision / (recall + precision) if recall + precision > 0 else 0.0
