"""``bench transcribe --leave-one-kit-out``: every figure on a kit that training never heard.

Two kinds of rows. *The rotation*: for each kit of :mod:`._kits` present here and not in the
held-out set, a model is trained (:mod:`livedrummer.acoustic.train`) on the candidates of every
*other* rotation kit's train-split takes (:mod:`._kitcorpus`). *The held-out set*
(``--held-out LIST``, by default :data:`._kits.HELD_OUT`): kits kept out of every training and
out of the choice of features and settings (tuning looks at the rotation's rows only); each is
tested with the model trained on every rotation kit, which is what ``acoustic train`` ships.
Either way the kit under test then plays test-split grooves in fresh conditions; the mix is
transcribed by that model and, for comparison, by the template recogniser with the bundled
``general-midi`` profile (made from TimGM6mb: on that kit its row is not held out), and one
microphone per drum is transcribed as ``input --audio --channels`` does (the template path:
per channel, the class is the channel's).
One row per kit, the held-out set first, then the worst figure of each column over the
held-out set, over the rotation and over both.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from ._kits import HELD_OUT

COLUMNS = ("kick", "snare", "hihat", "toms", "cymbals")


def add_options(ap: argparse.ArgumentParser) -> None:
    ap.add_argument(
        "--leave-one-kit-out",
        action="store_true",
        help="train on all kits but one, test on it, for every kit here",
    )
    ap.add_argument(
        "--kits",
        default=None,
        metavar="LIST",
        help="--leave-one-kit-out: the kits (default: every one present)",
    )
    ap.add_argument(
        "--train-files",
        type=int,
        default=24,
        metavar="N",
        help="--leave-one-kit-out: train excerpts per kit (default 24)",
    )
    ap.add_argument(
        "--held-out",
        default=",".join(HELD_OUT),
        metavar="LIST",
        help="--leave-one-kit-out: kits never trained or tuned on, tested with the "
        f"model of all the others, or none (default {','.join(HELD_OUT)})",
    )
    ap.add_argument(
        "--no-mics",
        action="store_true",
        help="--leave-one-kit-out: skip the one-mic-per-drum column",
    )


def train_without(excluded: set[str], kits: list, root: Path, count: int, seconds: float):  # type: ignore[no-untyped-def,type-arg]
    """The model trained on every kit of ``kits`` not in ``excluded``."""
    from livedrummer.acoustic.train import fit

    from ._kitcorpus import kit_candidates

    takes = [
        t for k in kits if k.name not in excluded for t in kit_candidates(k, root, count, seconds)
    ]
    return fit(takes, name="+".join(k.name for k in kits if k.name not in excluded))


def _parse_held_out(text: str) -> set[str]:
    from livedrummer.errors import LivedrummerError

    from ._kits import KIT_NAMES

    if text.strip() == "none":
        return set()
    names = {n.strip() for n in text.split(",") if n.strip()}
    for n in sorted(names - set(KIT_NAMES)):
        raise LivedrummerError(
            f"--held-out: unknown kit {n!r} (one of {', '.join(KIT_NAMES)}, or none)"
        )
    return names


def run(args: argparse.Namespace, root: Path) -> int:
    from ._kitcorpus import excerpts
    from ._kits import available_kits

    held = _parse_held_out(args.held_out)
    kits = available_kits(None if args.kits is None else args.kits.split(","))
    rotation = [k for k in kits if k.name not in held]
    held_here = [k for k in kits if k.name in held]
    if len(rotation) < 2:
        print(
            "bench transcribe --leave-one-kit-out: fewer than two kits present outside "
            "the held-out set"
        )
        return 2
    count = 6 if args.files is None else args.files
    tests = excerpts(root, "test", count, args.seconds)
    train_s = 12.0
    print(
        f"bench transcribe --leave-one-kit-out: rotation {', '.join(k.name for k in rotation)}"
        f"; held out {', '.join(k.name for k in held_here) or 'none'}; each model trained "
        f"on {args.train_files} train-split excerpts of {train_s:g} s per training kit; "
        f"tested on {count} test-split excerpts of {args.seconds:g} s of the kit it never "
        "heard (F, +-25 ms; mics: the worst channel)"
    )
    head = "  ".join(f"{c:>7}" for c in COLUMNS)
    print(f"  {'kit':<14} {head}  {'mics':>6}  | templates: kick  snare  hihat")
    worsts = []
    models: dict[frozenset[str], object] = {}  # one model per training set (the held-out rows')
    for title, group in (("held out", held_here), ("rotation", rotation)):
        if not group:
            continue
        print(f"  {title}:")
        worst = {c: 1.0 for c in (*COLUMNS, "mics", "t_kick", "t_snare", "t_hihat")}
        for kit in group:
            excluded = frozenset({kit.name} | held)
            t0 = time.perf_counter()
            if excluded not in models:
                models[excluded] = train_without(
                    set(excluded), kits, root, args.train_files, train_s
                )
            model = models[excluded]
            line = _row(kit, model, tests, args.no_mics, worst)
            print(f"  {kit.name:<14} {line}   ({time.perf_counter() - t0:.0f} s)", flush=True)
        _print_worst(f"worst {title}", worst, args.no_mics)
        worsts.append(worst)
    if len(worsts) > 1:
        _print_worst(
            "worst of all", {k: min(w[k] for w in worsts) for k in worsts[0]}, args.no_mics
        )
    return 0


def _print_worst(title: str, worst: dict[str, float], no_mics: bool) -> None:
    last = "  ".join(f"{worst[c]:7.3f}" for c in COLUMNS)
    mics = f"{'-':>6}" if no_mics else f"{worst['mics']:6.3f}"
    print(
        f"  {title:<14} {last}  {mics}  |      {worst['t_kick']:.3f}  "
        f"{worst['t_snare']:.3f}  {worst['t_hihat']:.3f}"
    )


def _row(kit, model, tests: list, no_mics: bool, worst: dict[str, float]) -> str:  # type: ignore[no-untyped-def,type-arg]
    """One kit's figures (the model's, the mics', the templates'); ``worst`` is lowered."""
    from livedrummer.acoustic.detector import detect
    from livedrummer.acoustic.pieces import CLASSES
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.score import Counts, score

    from ._drumaudio import MICS
    from ._kitcorpus import GROUPS_MIX, SR, render_stem_takes, render_takes

    profile = load_profile(None)
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
    if not no_mics:
        mic_tot: dict[str, Counts] = {}
        for take, (stems, names) in zip(takes, render_stem_takes(kit, tests, "test"), strict=True):
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
        n = tot[c].tp + tot[c].fn if c in tot else 0
        if n:
            worst[c] = min(worst[c], tot[c].f)
        row.append(f"{tot[c].f:7.3f}" if n else f"{'-':>7}")
    for c in ("kick", "snare", "hihat"):
        worst[f"t_{c}"] = min(worst[f"t_{c}"], old[c].f)
    return (
        f"{'  '.join(row)}  {mic_f:6.3f}  |      {old['kick'].f:.3f}  {old['snare'].f:.3f}  "
        f"{old['hihat'].f:.3f}"
    )
