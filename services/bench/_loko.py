"""``bench transcribe --leave-one-kit-out``: every figure on a kit that training never heard.

For each kit of :mod:`._kits` present here, a model is trained (:mod:`livedrummer.acoustic.train`)
on the candidates of every *other* kit's train-split takes (:mod:`._kitcorpus`), then the held-out
kit plays test-split grooves in fresh conditions; the mix is transcribed by that model and, for
comparison, by the template recogniser with the bundled ``general-midi`` profile (made from
TimGM6mb: on that kit its row is not held out), and one microphone per drum is transcribed as
``input --audio --channels`` does (the template path: per channel, the class is the channel's).
One row per kit, then the worst figure of each column over the kits.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

COLUMNS = ("kick", "snare", "hihat", "toms", "cymbals")


def add_options(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--leave-one-kit-out", action="store_true",
                    help="train on all kits but one, test on it, for every kit here")  # fmt: skip
    ap.add_argument("--kits", default=None, metavar="LIST",
                    help="--leave-one-kit-out: the kits (default: every one present)")  # fmt: skip
    ap.add_argument("--train-files", type=int, default=24, metavar="N",
                    help="--leave-one-kit-out: train excerpts per kit (default 24)")  # fmt: skip
    ap.add_argument("--no-mics", action="store_true",
                    help="--leave-one-kit-out: skip the one-mic-per-drum column")  # fmt: skip


def train_without(held_out: str, kits: list, root: Path, count: int, seconds: float):  # type: ignore[no-untyped-def,type-arg]
    from livedrummer.acoustic.train import fit

    from ._kitcorpus import kit_candidates

    parts = [kit_candidates(k, root, count, seconds) for k in kits if k.name != held_out]
    x = np.concatenate([p[0] for p in parts])
    y = np.concatenate([p[1] for p in parts])
    level = np.concatenate([p[2] for p in parts])
    return fit(x, y, level, name=f"all-but-{held_out}")


def run(args: argparse.Namespace, root: Path) -> int:
    from livedrummer.acoustic.detector import detect
    from livedrummer.acoustic.pieces import CLASSES
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.score import Counts, score

    from ._drumaudio import MICS
    from ._kitcorpus import SR, excerpts, render_stem_takes, render_takes
    from ._kits import available_kits
    from .transcribe import GROUPS_MIX

    kits = available_kits(None if args.kits is None else args.kits.split(","))
    if len(kits) < 2:
        print("bench transcribe --leave-one-kit-out: fewer than two kits present")
        return 2
    profile = load_profile(None)
    count = 6 if args.files is None else args.files
    tests = excerpts(root, "test", count, args.seconds)
    train_s = 12.0
    print(f"bench transcribe --leave-one-kit-out: kits {', '.join(k.name for k in kits)}; "
          f"each model trained on {args.train_files} train-split excerpts of {train_s:g} s per "
          f"other kit; tested on {count} test-split excerpts of {args.seconds:g} s of the "
          "held-out kit (F, +-25 ms; mics: the worst channel)")  # fmt: skip
    head = "  ".join(f"{c:>7}" for c in COLUMNS)
    print(f"  {'held out':<11} {head}  {'mics':>6}  | templates: kick  snare  hihat")
    worst = {c: 1.0 for c in (*COLUMNS, "mics", "t_kick", "t_snare", "t_hihat")}
    for kit in kits:
        t0 = time.perf_counter()
        model = train_without(kit.name, kits, root, args.train_files, train_s)
        takes = render_takes(kit, tests, "test")
        tot: dict[str, Counts] = {}
        old: dict[str, Counts] = {}
        for take in takes:
            ref = (take.ref_times, take.ref_classes, take.ref_velocities)
            for model_or_none, acc in ((model, tot), (None, old)):
                hits = detect(take.audio, SR, profile, model=model_or_none)
                for k, v in score(hits["time_s"], hits["cls"], *ref, GROUPS_MIX).items():
                    acc[k] = acc.get(k, Counts(0, 0, 0)) + v
        mic_f = float("nan")
        if not args.no_mics:
            mic_tot: dict[str, Counts] = {}
            for take, (stems, names) in zip(takes, render_stem_takes(kit, tests, "test"),
                                            strict=True):  # fmt: skip
                chans = [CLASSES.index(MICS[n][0]) for n in names]
                hits = detect(stems, SR, profile, chans)
                ref = (take.ref_times, take.ref_classes, take.ref_velocities)
                groups = {n: MICS[n] for n in names}
                for k, v in score(hits["time_s"], hits["cls"], *ref, groups).items():
                    if k != "all":
                        mic_tot[k] = mic_tot.get(k, Counts(0, 0, 0)) + v
            # a channel with few strokes in the test takes (a tom, a crash) counts as well
            mic_f = min(c.f for c in mic_tot.values())
            worst["mics"] = min(worst["mics"], mic_f)
        row = []
        for c in COLUMNS:
            f = tot[c].f if c in tot else float("nan")
            n = tot[c].tp + tot[c].fn if c in tot else 0
            worst[c] = min(worst[c], f) if n else worst[c]
            row.append(f"{f:7.3f}" if n else f"{'-':>7}")
        for c in ("kick", "snare", "hihat"):
            worst[f"t_{c}"] = min(worst[f"t_{c}"], old[c].f)
        print(f"  {kit.name:<11} {'  '.join(row)}  {mic_f:6.3f}  |      "
              f"{old['kick'].f:.3f}  {old['snare'].f:.3f}  {old['hihat'].f:.3f}"
              f"   ({time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip
    last = "  ".join(f"{worst[c]:7.3f}" for c in COLUMNS)
    print(f"  {'worst':<11} {last}  {worst['mics']:6.3f}  |      {worst['t_kick']:.3f}  "
          f"{worst['t_snare']:.3f}  {worst['t_hihat']:.3f}")  # fmt: skip
    return 0
