"""Body benchmark: joint poses sampled per second, and strokes for the whole corpus.

* ``sample``: one animated groove sampled at ``--samples`` times in one call (curves, leg IK,
  forward kinematics, no kit channels); figure = samples x 24 joints / seconds (goal >= 1e6).
* ``corpus``: every Groove MIDI Dataset file read first (not timed), then limb assignment
  (the optimal strategy), torso, arm IK at every onset, stroke keys,
  curves and the clearance search, timed together (goal < 30 s).
  The corpus runs once in this process and once split over ``--jobs`` worker processes (files
  are independent; default: one per core), so both the single-core and the whole-machine
  figure are printed.
Figures are from one run (``--repeat`` takes the median); nothing asserts on time.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from livedrummer.body.perform import perform
from livedrummer.body.rig import build_rig
from livedrummer.body.skeleton import N_JOINTS
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.resources import data_dir
from livedrummer.timeline.performance import Performance

from ._paths import DEFAULT_CORPUS, corpus


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench body")
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--kit", default="rock5")
    parser.add_argument("--map", default="roland-td")
    parser.add_argument("--samples", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--skip-corpus", action="store_true")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args(argv)
    note_map = load_note_map(args.map)
    rig = build_rig(load_kit(args.kit))

    demo = data_dir("kits") / "grooves" / "gmd-drummer1-funk-80.mid"
    perf = read_midi_file(demo, note_map)
    anim = perform(perf, rig, note_map).animation
    times = np.linspace(0.0, perf.duration_s, args.samples)
    runs = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        anim.world(times)
        runs.append(time.perf_counter() - t0)
    sec = statistics.median(runs)
    print(
        f"body sample: {args.samples} samples x {N_JOINTS} joints in {sec:.3f} s "
        f"(median of {args.repeat})"
    )
    print(f"  joint poses/s    {args.samples * N_JOINTS / sec:,.0f}")

    if args.skip_corpus:
        return 0
    files = sorted(corpus(args.corpus).rglob("*.mid"))
    performances = [read_midi_file(f, note_map) for f in files]
    onsets = sum(p.onsets.size for p in performances)
    t0 = time.perf_counter()
    for p in performances:
        perform(p, rig, note_map)
    total = time.perf_counter() - t0
    print(f"body corpus: {len(files)} files, {onsets} onsets, kit {rig.kit.name}")
    print(f"  sticking + strokes  {total:.2f} s  ({onsets / total:,.0f} onsets/s), 1 process")
    if args.jobs > 1:
        chunks = [performances[i :: args.jobs] for i in range(args.jobs)]
        t0 = time.perf_counter()
        with ProcessPoolExecutor(args.jobs) as pool:
            list(pool.map(_perform_all, chunks, [args.kit] * args.jobs, [args.map] * args.jobs))
        par = time.perf_counter() - t0
        print(
            f"  sticking + strokes  {par:.2f} s  ({onsets / par:,.0f} onsets/s), "
            f"{args.jobs} processes (incl. start-up and transfer)"
        )
    return 0


def _perform_all(performances: list[Performance], kit: str, map_name: str) -> int:
    note_map = load_note_map(map_name)
    rig = build_rig(load_kit(kit))
    for p in performances:
        perform(p, rig, note_map)
    return len(performances)
