"""``livedrummer bench transcribe``: accuracy, speed and load of the percussion recogniser.

Renders excerpts of Groove MIDI Dataset performances of one split (``--split test``, the
files not used to tune; info.csv's split column; by default every beat performance longer
than 25 s, 65 in the test split, about a minute and a half) through a General MIDI SoundFont
(:mod:`._drumaudio`: room, noise, one-mic stems with crosstalk), transcribes them as a mix and
one microphone per drum, and prints onset F-measure against the MIDI per drum and overall,
counted as :mod:`livedrummer.acoustic.score` says (±25 ms, ghost notes 30 dB down and pedal
chicks don't care, same-drum notes within 30 ms one onset). Then the offline twin's real-time
factor (seconds of computing per second of audio) and the online detector's CPU load fed
256-sample blocks (process time per second of audio, as a share of one core), medians over
the excerpts. ``--live`` instead plays the mixes into ``input --audio`` through a private ``jackd -d
dummy`` (:mod:`._audiolive`) and prints attack → onset-on-the-bus latency (the attack placed
by the player's JACK cycle; median and 99th percentile over every hit), where that time goes
(:data:`STAGES`: the lookahead until the block that decides the hit is played, JACK and
PortAudio to the daemon's callback, the hand-off to the detector's thread, the detector's
work, publishing, ZeroMQ to the subscriber; from ``input --trace`` and the message's send
time) and live accuracy. ``--audio-profile`` is used by the daemon too; ``--realtime PRIO``
runs the daemon with ``input --realtime PRIO`` and the bench's subscriber thread and ZeroMQ
I/O thread at ``SCHED_FIFO`` ``PRIO`` (the player keeps the normal policy);
``--jackd-realtime`` runs the dummy server with ``-R`` (its clients' audio threads, the
player's and the daemon's callbacks, then run at JACK's real-time priority too).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._paths import DEFAULT_CORPUS, corpus

if TYPE_CHECKING:
    from livedrummer.acoustic.profile import DetectorSettings

    from ._audiolive import LiveRun
from ._kitcorpus import GROUPS_MIX, pick_files


def main(argv: list[str]) -> int:
    from livedrummer.acoustic.detector import OnlineDetector, detect
    from livedrummer.acoustic.pieces import CLASSES
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.score import Counts, score

    from ._drumaudio import MICS, SR, excerpt, render_mix, render_stems

    ap = argparse.ArgumentParser(prog="livedrummer bench transcribe")
    ap.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    ap.add_argument("--split", default="test", choices=("train", "validation", "test"))
    ap.add_argument(
        "--files",
        type=int,
        default=None,
        help="excerpts (default: every one of the split, 65 of the test split; "
        "--live: 4, played in real time)",
    )
    ap.add_argument("--seconds", type=float, default=15.0, help="excerpt length (default 15)")
    ap.add_argument("--audio-profile", default=None)
    ap.add_argument(
        "--live",
        action="store_true",
        help="play the excerpts into input --audio through a JACK dummy server and "
        "measure attack -> onset-on-the-bus latency",
    )
    ap.add_argument(
        "--realtime",
        type=int,
        default=0,
        metavar="PRIO",
        help="--live: run the daemon with input --realtime PRIO and the bench's "
        "subscriber at SCHED_FIFO PRIO too (1..60; default 0: off)",
    )
    ap.add_argument(
        "--jackd-realtime",
        action="store_true",
        help="--live: run the dummy JACK server with -R (real-time scheduling, "
        "as a stage rig runs jackd)",
    )
    from . import _loko

    _loko.add_options(ap)
    args = ap.parse_args(argv)
    if args.files is not None and args.files < 1:
        ap.error(f"--files {args.files}: expected 1 or more")
    if not 0 <= args.realtime <= 60:
        ap.error(f"--realtime {args.realtime}: expected 1..60 (0: off)")
    if args.live:
        return live(args)
    root = corpus(args.corpus)
    if args.leave_one_kit_out:
        return _loko.run(args, root)
    profile = load_profile(args.audio_profile)
    mix_tot: dict[str, Counts] = {}
    mic_tot: dict[str, Counts] = {}
    rtf: list[float] = []
    load: list[float] = []
    files = pick_files(root, args.split, args.files)
    for i, path in enumerate(files):
        ex = excerpt(path, 5.0, args.seconds)
        mix = render_mix(ex, seed=i)
        t0 = time.perf_counter()
        hits = detect(mix, SR, profile)
        rtf.append((time.perf_counter() - t0) / ex.duration_s)
        ref = (ex.onsets["time_s"], ex.classes, ex.onsets["velocity"])
        for k, v in score(hits["time_s"], hits["cls"], *ref, GROUPS_MIX).items():
            mix_tot[k] = mix_tot.get(k, Counts(0, 0, 0)) + v
        online = OnlineDetector(profile, SR)
        t0 = time.process_time()
        for start in range(0, len(mix), 256):
            online.process(mix[start : start + 256])
        load.append((time.process_time() - t0) / ex.duration_s)
        stems, names = render_stems(ex, seed=i)
        chans = [CLASSES.index(MICS[n][0]) for n in names]
        hits = detect(stems, SR, profile, chans)
        for k, v in score(hits["time_s"], hits["cls"], *ref, {n: MICS[n] for n in names}).items():
            mic_tot[k] = mic_tot.get(k, Counts(0, 0, 0)) + v
    print(
        f"bench transcribe: {len(files)} excerpts of {args.seconds:g} s from the "
        f"{args.split} split, profile {profile.name}"
    )
    for title, tot in (("mix", mix_tot), ("one mic per drum", mic_tot)):
        print(f"  {title}: onset F-measure (precision / recall, true onsets counted)")
        for k, c in tot.items():
            print(
                f"    {k:<10} F {c.f:.3f}  P {c.precision:.3f}  R {c.recall:.3f}  n {c.tp + c.fn}"
            )
    print(
        f"  offline twin real-time factor: median {np.median(rtf):.4f} "
        f"({1 / np.median(rtf):.0f}x faster than real time)"
    )
    print(
        f"  online detector CPU load (256-sample blocks): median {100 * np.median(load):.1f} "
        "% of one core"
    )
    return 0


def live(args: argparse.Namespace) -> int:
    import os

    from livedrummer.acoustic.detector import detect
    from livedrummer.acoustic.model import load_model
    from livedrummer.acoustic.pieces import classes_of
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.score import Counts, score

    from ._audiolive import play_into_daemon
    from ._drumaudio import SR, excerpt, render_mix
    from ._jack import dummy_jack, jack_env

    root = corpus(args.corpus)
    profile = load_profile(args.audio_profile)
    # the daemon's recogniser (input --recogniser auto): the model unless a profile is named
    model = None if args.audio_profile is not None else load_model(None)
    latencies: list[float] = []
    stages: list[np.ndarray] = []
    tot: dict[str, Counts] = {}
    files = pick_files(root, args.split, 4 if args.files is None else args.files)
    with dummy_jack("bench-transcribe", realtime=args.jackd_realtime) as name:
        os.environ.update(jack_env(name))
        for i, path in enumerate(files):
            ex = excerpt(path, 5.0, args.seconds)
            mix = render_mix(ex, seed=i)
            extra = [] if args.audio_profile is None else ["--audio-profile", args.audio_profile]
            run = play_into_daemon(mix, extra, trace=True, realtime=args.realtime)
            if args.realtime and run.daemon_policy != os.SCHED_FIFO:
                print(f"  {path.name}: the daemon did not get SCHED_FIFO: {run.stderr.strip()}")
            offline = np.sort(detect(mix, SR, profile, model=model)["time_s"])
            if len(run.onsets) != len(offline):
                print(f"  {path.name}: {len(run.onsets)} live hits, {len(offline)} offline")
                continue
            latencies += (np.sort(run.arrival_s) - run.attack_times(offline)).tolist()
            if len(run.trace) == len(offline):
                stages.append(_stages(run, offline, profile.settings))
            # live stamps back on the file's time line through the player's JACK cycles
            on = run.onsets
            ref = (ex.onsets["time_s"], ex.classes, ex.onsets["velocity"])
            got = score(run.file_times(on["time_s"]), classes_of(on), *ref, GROUPS_MIX)
            for k, v in got.items():
                tot[k] = tot.get(k, Counts(0, 0, 0)) + v
    lat = np.array(latencies) * 1000
    rt = f", SCHED_FIFO {args.realtime}" if args.realtime else ""
    rt += ", jackd -R" if args.jackd_realtime else ""
    print(
        f"bench transcribe --live: {len(files)} excerpts of {args.seconds:g} s ({args.split}), "
        f"input --audio through jackd -d dummy (128 frames, 48 kHz){rt}, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    if len(lat):
        p50, p99 = np.percentile(lat, 50), np.percentile(lat, 99)
        print(
            f"  attack -> onset on the bus: p50 {p50:.1f} ms, p99 {p99:.1f} ms, "
            f"max {lat.max():.1f} ms ({len(lat)} hits)"
        )
    if stages:
        print("  where the time goes (ms, p50 / p99 over the hits):")
        table = np.concatenate(stages) * 1000
        for name, col in zip(STAGES, table.T, strict=True):
            print(f"    {name:<46} {np.percentile(col, 50):5.1f} / {np.percentile(col, 99):5.1f}")
        ours = table[:, 1:].sum(axis=1)  # from the deciding block's cycle on
        print(
            f"    {'deciding block played -> subscriber has it':<46} "
            f"{np.percentile(ours, 50):5.1f} / {np.percentile(ours, 99):5.1f}"
        )
    for k, c in tot.items():
        print(f"    {k:<10} F {c.f:.3f}  P {c.precision:.3f}  R {c.recall:.3f}  n {c.tp + c.fn}")
    return 0


STAGES = (
    "attack -> its deciding block played (lookahead)",
    "played -> daemon's audio callback (JACK, PA)",
    "callback -> detector thread takes it (hand-off)",
    "taken -> detector gives the hit (Python work)",
    "hit -> sent on the bus (publish)",
    "sent -> subscriber has it (ZeroMQ, wake-up)",
)


def _stages(run: LiveRun, offline: np.ndarray, s: DetectorSettings) -> np.ndarray:
    """Per hit (rows), the seconds each of :data:`STAGES` took: the attack (the offline twin's
    stamp, placed by the player's cycles), the player's callback for the block holding the
    sample that decides the hit (``lookahead`` frames after the onset frame), then the
    daemon's own times (``input --trace``), the message's send time and its arrival."""
    from livedrummer.acoustic.spectrum import HOP

    from ._drumaudio import SR

    decided = np.round((offline + s.offset_ms / 1000) * SR).astype(np.int64) + s.lookahead * HOP
    marks = [
        run.attack_times(offline),
        run.block_time(decided - 1),
        *run.trace.T,
        run.sent_s,
        run.arrival_s,
    ]
    return np.diff(np.array(marks), axis=0).T
