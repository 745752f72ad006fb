"""How often is the upswing visible when GMD grooves are played live into the synth?

Each groove (Groove MIDI Dataset beside the checkout, Roland TD map) is fed to a
:class:`~livedrummer.live.synth.LiveSynth` one onset at a time on a stepped clock, polled at
the service's tick rate, as if played live; the offline animation of the same (online)
sticking is the reference. :func:`~bench._upswing.upswing_visible` counts the hand
notes whose live stick, one preparation window (50 ms) before the contact, is at least half
as high as offline. Printed with and without prediction. Figures from one run; no assertions.
"""

from __future__ import annotations

import argparse
import random
from pathlib import Path

import numpy as np

from livedrummer.body.animation import animate, hihat_openness
from livedrummer.body.rig import Rig, build_rig
from livedrummer.body.skeleton import J
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.online import stick_online

from ._paths import DEFAULT_CORPUS, corpus
from ._upswing import Upswing, upswing_visible

TIPS = {0: J["r_tip"], 1: J["l_tip"]}
PREP_S = 0.05
START = 1000.0


def measure(rig: Rig, path: Path, seconds: float, params: SynthParams, tick_hz: float) -> Upswing:
    perf = read_midi_file(path, load_note_map("roland-td"))
    on = perf.onsets[perf.onsets["time_s"] < seconds].copy()
    if on.size < 8:
        return Upswing(0, 0)
    on["time_s"] += START
    synth = LiveSynth(rig, params)
    shows, zs = [], []
    now, i = float(on["time_s"][0]) - 0.2, 0
    while now < float(on["time_s"][-1]) + 0.2:
        while i < on.size and on["time_s"][i] <= now:
            synth.process(on[i])
            i += 1
        batch = synth.poses_until(now)
        shows.append(batch.show_s)
        zs.append(batch.rows["position"][:, [TIPS[0], TIPS[1]], 2])
        now += 1.0 / tick_hz
    show = np.concatenate(shows)
    z = np.concatenate(zs)
    st = stick_online(on, rig.kit, params.lookahead_s)
    anim = animate(rig, st, perf.grid.beat_s + START, hihat_openness(on, perf.controls[:0]))
    hands = np.flatnonzero((st.limb >= 0) & (st.limb <= 1) & (st.piece >= 0))
    t = st.onsets["time_s"][hands].astype(np.float64)
    keep = t - PREP_S > show[0] - params.delay_s
    hands, t = hands[keep], t[keep]
    tips = np.array([TIPS[int(st.limb[k])] for k in hands], dtype=np.int64)
    _, at = anim.world(t)
    _, before = anim.world(t - PREP_S)
    rows = np.arange(t.size)
    j = np.clip(np.searchsorted(show, t - PREP_S + params.delay_s - 1e-9), 0, show.size - 1)
    live = z[j, st.limb[hands].astype(np.int64)]
    return upswing_visible(before[rows, tips, 2], at[rows, tips, 2], live)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench upswing", description=__doc__)
    parser.add_argument("--files", type=int, default=12, help="grooves drawn at random")
    parser.add_argument(
        "--corpus",
        type=Path,
        default=DEFAULT_CORPUS,
        help="the dataset (default ../shared/data/groove)",
    )
    parser.add_argument("--seconds", type=float, default=15.0, help="of each groove")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--delay-ms",
        type=float,
        nargs="+",
        default=[30.0],
        metavar="D",
        help="visual delay(s), measured in turn (default 30)",
    )
    parser.add_argument(
        "--lookahead-ms",
        type=float,
        default=None,
        metavar="L",
        help="the sticking's lookahead (default: min(30, D))",
    )
    parser.add_argument("--tick-hz", type=float, default=120.0)
    parser.add_argument(
        "--prediction",
        choices=("both", "on", "off"),
        default="both",
        help="with the hand predictor, without, or both (default)",
    )
    args = parser.parse_args(argv)
    files = sorted(corpus(args.corpus).rglob("*.mid"))
    beats = [f for f in files if "_beat_" in f.name]
    chosen = random.Random(args.seed).sample(beats, min(args.files, len(beats)))
    rig = build_rig(load_kit("rock5"))
    print(
        f"{len(chosen)} GMD beats, first {args.seconds:g} s each; L = min(30 ms, D) unless "
        f"given; upswing visible = live stick >= 1/2 offline height {PREP_S * 1000:g} ms before "
        f"contact"
    )
    modes = {"both": (False, True), "on": (True,), "off": (False,)}[args.prediction]
    for delay_ms, predict in ((d, p) for d in args.delay_ms for p in modes):
        lookahead_ms = args.lookahead_ms or min(30.0, delay_ms)
        params = SynthParams(lookahead_ms / 1000, delay_ms / 1000, predict=predict)
        total = Upswing(0, 0)
        for path in chosen:
            u = measure(rig, path, args.seconds, params, args.tick_hz)
            total = Upswing(total.notes + u.notes, total.visible + u.visible)
        print(
            f"D = {delay_ms:g} ms, L = {lookahead_ms:g} ms, prediction "
            f"{'on ' if predict else 'off'}: "
            f"{total.visible}/{total.notes} notes "
            f"= {100 * total.fraction:.1f} %",
            flush=True,
        )
    return 0
