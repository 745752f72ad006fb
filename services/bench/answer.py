"""Where a hit's answer goes: the synth's answer path, stage by stage, per hit.

The answer to a hit is everything between reading its ONSET message and publishing its
contact pose: decoding, the note joining the window (the online sticking's step), its
decided or provisional limb, the copy of what the quick contact reads, the contact solve
(one IK per limb: :func:`~livedrummer.body.strike.strike_poses`), the batch cut from the
ledger (``take_quick``) and the POSE message's encoding. This bench drives a
:class:`~livedrummer.live.synth.LiveSynth` in one process in real time, without sockets, as
the service's answer thread does (each hit answered the moment its time comes, stamped with
its arrival) with the animation thread's ticks (``poses_until``, every 1/120 s and after each
hit) in between, and times each stage of every answer (the functions wrapped for the run
only), the ticks, and the garbage collector's pauses. Rates: alternating snare and hi-hat at
each ``--rates`` (notes/s), and the demo groove. Prints p50/p99 and the total per stage;
figures from one run, no assertions; on a loaded machine the p99s are mostly the scheduler's.
"""

from __future__ import annotations

import argparse
import gc
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from livedrummer import protocol as p
from livedrummer.body.rig import Rig, build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.live import quick, synth, window
from livedrummer.live.beat import BeatTracker
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.online import OnlineSticker
from livedrummer.timeline.events import ONSET_DTYPE

Times = defaultdict[str, list[float]]

#: (owner, attribute, label) of each stage timed; indented labels are parts of the one above
STAGES: tuple[tuple[Any, str, str], ...] = (
    (window.NoteWindow, "add", "note joins the window"),
    (OnlineSticker, "process", "  online sticking step"),
    (window.NoteWindow, "limbs", "decided/provisional limb"),
    (LiveSynth, "quick_state", "copy for the contact"),
    (synth, "quick_contact", "contact solve"),
    (quick, "strike_poses", "  IK (strike_poses)"),
    (LiveSynth, "take_quick", "batch from the ledger"),
    (BeatTracker, "process", "beat tracker (on the tick)"),
)


@contextmanager
def timed(times: Times) -> Iterator[None]:
    """Every stage of :data:`STAGES` timed into ``times`` while inside."""
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in STAGES]

    def wrap(f: Callable[..., Any], label: str) -> Callable[..., Any]:
        def run(*args: Any, **kwargs: Any) -> Any:
            t = time.perf_counter()
            try:
                return f(*args, **kwargs)
            finally:
                times[label].append(time.perf_counter() - t)

        return run

    try:
        for (owner, name, f), (_, _, label) in zip(saved, STAGES, strict=True):
            setattr(owner, name, wrap(f, label))
        yield
    finally:
        for owner, name, f in saved:
            setattr(owner, name, f)


def drive(rig: Rig, onsets: np.ndarray, times: Times) -> np.ndarray:
    """Play ``onsets`` (times from 0) into a fresh synth in real time; the answer times (s)."""
    syn = LiveSynth(rig, SynthParams())
    fmt = p.PoseFormat.from_dtype(syn.dtype)
    start = time.perf_counter() + 0.2 - float(onsets["time_s"][0])
    answers: list[float] = []
    gc_at = [0.0]

    def on_gc(phase: str, _info: dict[str, int]) -> None:
        if phase == "start":
            gc_at[0] = time.perf_counter()
        else:
            times["garbage collection"].append(time.perf_counter() - gc_at[0])

    gc.callbacks.append(on_gc)
    try:
        i, next_tick, end = 0, 0.0, float(onsets["time_s"][-1]) + 0.3
        with timed(times):
            while (now := time.perf_counter() - start) < end:
                if i < onsets.size and onsets["time_s"][i] <= now:
                    j = int(np.searchsorted(onsets["time_s"], now, side="right"))
                    rows = onsets[i:j].copy()
                    rows["time_s"] = now  # stamped on arrival
                    frames = p.encode(p.Message(p.Kind.ONSET, rows, seq=i))
                    t0 = time.perf_counter()
                    body = p.decode(frames).body
                    t1 = time.perf_counter()
                    assert isinstance(body, np.ndarray)
                    syn.process(body.copy())
                    batch = syn.take_quick()
                    t2 = time.perf_counter()
                    if batch.show_s.size:
                        pose = p.Pose(float(batch.show_s[0]), batch.rows)
                        p.encode(p.Message(p.Kind.POSE, pose, seq=i, stream=p.Stream.POSES), fmt)
                    t3 = time.perf_counter()
                    times["decode ONSET"].append(t1 - t0)
                    times["encode POSE"].append(t3 - t2)
                    answers.append(t3 - t0)
                    i, next_tick = j, 0.0  # the animation thread ticks at once
                    continue
                if now >= next_tick:
                    t0 = time.perf_counter()
                    syn.poses_until(now)
                    times["tick (poses_until, not on the answer path)"].append(
                        time.perf_counter() - t0
                    )
                    next_tick = now + 1 / 120
                else:
                    time.sleep(min(0.0005, next_tick - now))
    finally:
        gc.callbacks.remove(on_gc)
    return np.array(answers)


def alternating(groove: np.ndarray, rate: float, seconds: float) -> np.ndarray:
    """Snare and closed hi-hat in turn at ``rate`` notes/s: the groove's first note of each
    (Roland TD notes 38 and 42) repeated, its velocity varied."""
    snare = groove[groove["note"] == 38][0]
    hihat = groove[groove["note"] == 42][0]
    n = max(5, int(rate * seconds))
    out: np.ndarray = np.where(np.arange(n) % 2 == 0, snare, hihat).astype(ONSET_DTYPE)
    out["time_s"] = np.arange(n) / rate
    out["velocity"] = 64 + np.arange(n) % 60
    return out


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench answer", description=__doc__)
    parser.add_argument("--rates", type=float, nargs="+", default=[1.0, 100.0])
    parser.add_argument("--seconds", type=float, default=3.0, help="per rate")
    parser.add_argument(
        "--groove",
        type=float,
        default=20.0,
        metavar="S",
        help="also the first S s of the demo groove (0: not)",
    )
    args = parser.parse_args(argv)
    from ..cli.files import DEMO_MAP, demo_groove

    note_map = load_note_map(DEMO_MAP)
    rig = build_rig(load_kit("rock5"))
    groove = read_midi_file(demo_groove(), note_map).onsets
    runs = [(f"{rate:g} notes/s", alternating(groove, rate, args.seconds)) for rate in args.rates]
    if args.groove > 0:
        g = groove[groove["time_s"] < groove["time_s"][0] + args.groove].copy()
        runs.append(("demo groove", g))
    for label, onsets in runs:
        times: Times = defaultdict(list)
        answers = drive(rig, onsets, times) * 1000
        print(
            f"\n{label}: {answers.size} answers (hits arriving together are one), answered in "
            f"p50 {np.percentile(answers, 50):.2f} ms, p99 {np.percentile(answers, 99):.2f} ms, "
            f"max {answers.max():.2f} ms"
        )
        print(f"  {'stage':46} {'calls':>6} {'p50 ms':>8} {'p99 ms':>8} {'total ms':>9}")
        order = ["decode ONSET", *(label for _, _, label in STAGES), "encode POSE"]
        for name in [*order, *(k for k in times if k not in order)]:
            if name not in times:
                continue
            v = np.array(times[name]) * 1000
            print(
                f"  {name:46} {v.size:6d} {np.percentile(v, 50):8.3f} "
                f"{np.percentile(v, 99):8.3f} {v.sum():9.1f}"
            )
    return 0
