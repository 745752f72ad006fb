"""``livedrummer acoustic train``: the learned hit classifier, made again from the kits here.

Renders the multi-kit corpus (:mod:`services.bench._kitcorpus`: GMD train-split grooves
through every kit of :mod:`services.bench._kits` present, each take in its own room, EQ,
compression and noise), collects the detector's onset candidates with their labels and fits
the model (:mod:`livedrummer.acoustic.train`), seeded: the same kits and options give the same
file. The bundled ``kits/audio/acoustic-model.npz`` is made by the defaults, which hold out
the named held-out set (:data:`services.bench._kits.HELD_OUT`: the tests check the model on
TimGM6mb, ``bench transcribe --leave-one-kit-out`` on all of them); ``--hold-out none`` trains
on every kit.
A kit absent here is skipped with a line saying which package has it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .parsing import Subparsers, add_command

#: :data:`services.bench._kits.HELD_OUT`, spelt out (the parser loads no numpy; a test checks
#: that the two agree).
DEFAULT_HOLD_OUT = "timgm6mb,bjapacific,rumpf"


def register(sub: Subparsers) -> None:
    p = add_command(sub, "acoustic", _usage)
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    train = actions.add_parser("train", help="train the hit classifier on the kits here")
    train.add_argument(
        "-o",
        "--output",
        type=Path,
        default=None,
        help="model .npz to write (default: the bundled kits/audio/acoustic-model.npz)",
    )
    train.add_argument(
        "--kits", default=None, metavar="LIST", help="kits to train on (default: every one present)"
    )
    train.add_argument(
        "--hold-out",
        default=DEFAULT_HOLD_OUT,
        metavar="LIST",
        help=f"kits left out of training, or none (default {DEFAULT_HOLD_OUT})",
    )
    train.add_argument(
        "--files",
        type=int,
        default=24,
        metavar="N",
        help="train-split excerpts per kit (default 24)",
    )
    train.add_argument("--seconds", type=float, default=12.0, help="excerpt length (default 12)")
    train.add_argument("--epochs", type=int, default=8, help="passes over the data (default 8)")
    train.add_argument(
        "--copies",
        type=int,
        default=1,
        metavar="N",
        help="each take N times, the extra ones through a fresh EQ and gain "
        "(default 1: none; 3 cost the kick on unheard kits)",
    )
    train.add_argument("--seed", type=int, default=0)
    train.add_argument(
        "--corpus",
        type=Path,
        default=None,
        help="the Groove MIDI Dataset folder (default: ../shared/data/groove beside the checkout)",
    )
    train.set_defaults(func=run_train)


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer acoustic train ...")
    return 2


def run_train(args: argparse.Namespace) -> int:
    from livedrummer.acoustic.train import fit
    from livedrummer.errors import LivedrummerError
    from livedrummer.resources import data_dir

    from ..bench._kitcorpus import kit_candidates
    from ..bench._kits import KIT_NAMES, available_kits
    from ..bench._paths import DEFAULT_CORPUS, corpus

    if args.files < 1 or args.seconds <= 0 or args.epochs < 1 or args.copies < 1:
        raise LivedrummerError("--files, --seconds, --epochs and --copies must be positive")
    names = None if args.kits is None else [k.strip() for k in args.kits.split(",") if k.strip()]
    held = set() if args.hold_out == "none" else {h.strip() for h in args.hold_out.split(",")}
    for h in sorted(held - set(KIT_NAMES)):
        raise LivedrummerError(
            f"--hold-out: unknown kit {h!r} (one of {', '.join(KIT_NAMES)}, or none)"
        )
    kits = [k for k in available_kits(names) if k.name not in held]
    if not kits:
        raise LivedrummerError("--kits: no kit to train on is present here")
    root = corpus(args.corpus or DEFAULT_CORPUS)
    takes = []
    for kit in kits:
        part = kit_candidates(kit, root, args.files, args.seconds)
        print(f"  {kit.name}: {sum(len(t.features) for t in part)} onset candidates", flush=True)
        takes += part
    name = "+".join(k.name for k in kits)
    model = fit(takes, seed=args.seed, epochs=args.epochs, name=name, copies=args.copies)
    out = args.output or data_dir("kits") / "audio" / "acoustic-model.npz"
    try:
        model.save(out)
    except OSError as exc:
        raise LivedrummerError(f"{out}: cannot write: {exc.strerror or exc}") from None
    print(f"{out}: trained on {name} ({sum(len(t.features) for t in takes)} candidates)")
    return 0
