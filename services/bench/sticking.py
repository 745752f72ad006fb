"""Sticking benchmark: every strategy against the annotated corpus and on the whole GMD.

Prints three tables. (1) Per strategy on the annotated corpus (``tests/data/sticking``):
accuracy against the teacher's hand annotations, unconventional crossings, same-hand-too-fast
strokes and dropped notes (definitions in :mod:`livedrummer.sticking.metrics`); the online form
of ``optimal`` is listed at 30 ms and 0 ms lookahead. (2) The same counts on every Groove MIDI
Dataset file, with notes per second of the strategy alone (files are read beforehand).
(3) The online form's per-note decision time (each ``process`` call), p50 and p99 in µs, at
lookahead 0 and 30 ms over ``--online-files`` GMD files. Figures come from one run.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from livedrummer.errors import ConfigError
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking import metrics
from livedrummer.sticking.online import OnlineSticker, stick_online
from livedrummer.sticking.result import Sticking
from livedrummer.sticking.strategy import STRATEGIES, assign, stick_performance
from livedrummer.sticking.tab import read_tab
from livedrummer.timeline.performance import Performance

from ._paths import DEFAULT_CORPUS, WORKDIR, corpus

DEFAULT_ANNOTATED = WORKDIR / "tests" / "data" / "sticking"


def counts(result: Sticking, kit: Kit) -> tuple[int, int, int]:
    return (
        int(metrics.crossings(result, kit).sum()),
        int(metrics.too_fast(result, kit).sum()),
        int(metrics.dropped(result).sum()),
    )


def annotated_table(folder: Path) -> None:
    tabs = [read_tab(f) for f in sorted(folder.glob("*.tab"))]
    if not tabs:
        raise ConfigError(
            f"{folder}: no annotated .tab files; pass --annotated DIR (the "
            "checkout's tests/data/sticking) or --tables gmd,online"
        )
    print(f"annotated corpus: {len(tabs)} patterns, {sum(t.onsets.size for t in tabs)} notes")
    print(f"  {'strategy':<22} {'accuracy':>9} {'crossings':>10} {'too fast':>9} {'dropped':>8}")
    runs: list[tuple[str, object]] = [(name, name) for name in STRATEGIES]
    runs += [("optimal online 30 ms", 0.030), ("optimal online 0 ms", 0.0)]
    for label, how in runs:
        hit = total = cross = fast = drop = 0
        for tab in tabs:
            kit = load_kit(tab.kit)
            if isinstance(how, str):
                result = assign(tab.onsets, kit, how, beat_s=tab.beat_s)
            else:
                result = stick_online(tab.onsets, kit, float(how), beat_s=tab.beat_s)  # type: ignore[arg-type]
            m, n = metrics.accuracy(result, tab.limbs)
            c, f, d = counts(result, kit)
            hit, total, cross, fast, drop = hit + m, total + n, cross + c, fast + f, drop + d
        print(f"  {label:<22} {100 * hit / total:>8.1f}% {cross:>10} {fast:>9} {drop:>8}")


def gmd_table(perfs: list[Performance], kit: Kit) -> None:
    notes = sum(p.onsets.size for p in perfs)
    print(f"\nGroove MIDI Dataset: {len(perfs)} files, {notes} notes, kit {kit.name}")
    print(f"  {'strategy':<22} {'crossings':>10} {'too fast':>9} {'dropped':>8} {'notes/s':>10}")
    for name in STRATEGIES:
        cross = fast = drop = 0
        elapsed = 0.0
        for p in perfs:
            t0 = time.perf_counter()
            result = stick_performance(p, kit, name)
            elapsed += time.perf_counter() - t0
            c, f, d = counts(result, kit)
            cross, fast, drop = cross + c, fast + f, drop + d
        print(f"  {name:<22} {cross:>10} {fast:>9} {drop:>8} {notes / elapsed:>10,.0f}")


def online_table(sample: list[Performance], kit: Kit) -> None:
    count = sum(p.onsets.size for p in sample)
    print(f"\nonline decision time per note ({len(sample)} files, {count} notes)")
    print(f"  {'lookahead':<10} {'p50 us':>8} {'p99 us':>8} {'max us':>9}")
    for lookahead in (0.0, 0.030):
        spent: list[int] = []
        for p in sample:
            sticker = OnlineSticker(kit, lookahead, beat_s=p.grid.beat_s)
            for row in p.onsets:
                t0 = time.perf_counter_ns()
                sticker.process(row)
                spent.append(time.perf_counter_ns() - t0)
            sticker.flush()
        us = np.array(spent) / 1e3
        p50, p99 = np.percentile(us, [50, 99])
        print(f"  {lookahead * 1e3:>5.0f} ms   {p50:>8.1f} {p99:>8.1f} {us.max():>9.1f}")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench sticking")
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--annotated", type=Path, default=DEFAULT_ANNOTATED)
    parser.add_argument("--map", default="roland-td")
    parser.add_argument("--kit", default="rock5")
    parser.add_argument("--limit", type=int, default=0, help="only the first N GMD files")
    parser.add_argument("--online-files", type=int, default=100)
    parser.add_argument(
        "--tables", default="annotated,gmd,online", help="which tables, comma-separated"
    )
    args = parser.parse_args(argv)
    tables = set(args.tables.split(","))
    if "annotated" in tables:
        annotated_table(args.annotated)
    if not tables & {"gmd", "online"}:
        return 0
    files = sorted(corpus(args.corpus).rglob("*.mid"))
    if args.limit:
        files = files[: args.limit]
    if "gmd" not in tables:
        files = files[: args.online_files]
    note_map = load_note_map(args.map)
    kit = load_kit(args.kit)
    perfs = [read_midi_file(f, note_map) for f in files]
    if "gmd" in tables:
        gmd_table(perfs, kit)
    if "online" in tables:
        online_table(perfs[: args.online_files], kit)
    return 0
