"""End-to-end latency of the live pipeline: JACK note-on → bus → pose → rendered frame.

Starts a ``jackd -d dummy -S`` server (Debian jackd2) with a virtual rtmidi output port as
the kit, then for each rate (default 1, 100 and 1,000 notes/s) a fresh pipeline of three
processes: ``livedrummer input`` on that port, ``livedrummer synth`` and ``livedrummer
display --live --headless`` (frames rendered off screen, not written, logged in
``frames.jsonl``). Notes alternate snare and hi-hat, so each should get a hand and a contact
sample. Measured per note, on the shared clock, from the moment the note-on is sent:

* JACK loopback: an rtmidi input port on the same server, connected to the kit (reference);
* onset on the bus: a subscriber to the input daemon receives the ONSET;
* pose available: a subscriber to the synth receives the POSE message holding the note's
  contact sample (show time = onset stamp + D);
* frame rendered: the display has finished the first frame that drew that sample or a later
  one (``frame - onset``: the same from the onset's stamp);
* pose - onset: pose available minus the onset's own stamp (with provisional poses the
  first, possibly provisional, contact sample). ``late`` counts notes whose contact sample
  arrived after onset + D, when it should already be on screen;
* pose - bus: pose available minus onset on the bus, both seen by the same subscriber: the
  synth's own share (one hop in, its work, one hop out);
* in the input daemon: its ONSET message's send time minus the onset's stamp (the daemon's
  own share of "onset on the bus"; the rest is ZeroMQ and the subscriber waking up).
* note-ons sent late: the bench's own sending thread against its schedule; and how many
  notes were stamped within the sticking's chord window (15 ms) of the two notes before
  them though planned further apart, with how many of those got no pose: on a loaded
  machine the sender and JACK's non-realtime dummy server deliver notes in bursts, their
  stamps are close together, and the sticking, which gives two hands one stroke each per
  instant, merges the third into the nearer stroke (a flam of that hand: it has a pose; the
  synth's summary line counts these "notes merged into a stroke"). Before that merge, it
  left the third out (the 100 notes/s runs' "no pose" notes were these).

Prints p50/p99 per stage and rate and the counts lost at each stage (sent vs on the bus, on
the bus vs contact samples; a note the sticking merges into another stroke, e.g. a third
hand note of a chord, has the contact sample of its own onset, struck by the nearer hand).
Figures from one run; no assertions.

Show control on: ``--osc`` gives the synth and the display an OSC port each (read every tick
and every frame, as in a show), ``--overlay score,joints`` has the display draw SMED's strips
over every frame. ``--both`` measures every rate twice in one run, with nothing and with
both on (OSC and the strips; ``--overlay`` picks which), in alternating order so that a load
that changes during the run weighs on both alike, and ends with the medians side by side and
the load average: the cost of the show control, measured under the same load.

Regressions: ``--compare REV [REV ...]`` runs the same bench (every other option as given)
from each commit ``REV``, checked out in a temporary git worktree, and from this checkout,
alternating (``--compare-runs`` times each, default 2), and ends with each REV's medians
beside this checkout's and their ratio (:mod:`services.bench._compare`).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import tempfile
import threading
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.kit.loader import load_kit
from livedrummer.sticking.prepare import CHORD_WINDOW_S
from livedrummer.timeline.clock import MonotonicClock

from ..process.program import program_argv
from ._compare import run_compare
from ._jack import dummy_jack, jack_env
from ._paths import CHECKOUT, WORKDIR

REPO = WORKDIR  # child processes start in the checkout (or the user's folder)
NOTES = (38, 42)  # snare head, closed hi-hat (roland-td)


def _spawn(args: list[str], home: str, err: Path) -> subprocess.Popen[str]:
    env = {**os.environ, "LIVEDRUMMER_HOME": home}
    env.pop("DISPLAY", None)
    return subprocess.Popen(
        [*program_argv(), *args],
        text=True,
        env=env,
        stdout=subprocess.PIPE,
        stderr=err.open("w"),
        cwd=REPO,
    )


def _line(proc: subprocess.Popen[str]) -> dict[str, Any]:
    assert proc.stdout is not None
    out: dict[str, Any] = json.loads(proc.stdout.readline())
    return out


class Jack:
    def __init__(self) -> None:
        import rtmidi

        self._stack = ExitStack()
        name = self._stack.enter_context(dummy_jack("ldlat", period=64))
        os.environ.update(jack_env(name))  # the pipeline's processes inherit it
        self.out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
        self.out.open_virtual_port("pads")
        self.loop = rtmidi.MidiIn(rtmidi.API_UNIX_JACK, "loopback")
        self.loop.open_virtual_port("in")
        self.loop_times: list[float] = []
        clock = MonotonicClock()
        self.loop.set_callback(lambda _msg, _data: self.loop_times.append(clock.now()))
        subprocess.run(["jack_connect", "kit:pads", "loopback:in"], check=True)

    def close(self) -> None:
        self.loop.close_port()
        self.out.close_port()
        self._stack.close()


def run_rate(
    jack: Jack,
    label: str,
    schedule: list[tuple[float, int, int]],
    delay_ms: float,
    lookahead_ms: float,
    tmp: Path,
    synth_args: list[str],
    input_args: list[str],
    display_args: list[str],
) -> dict[str, Any]:
    """One pipeline fed ``schedule``: (seconds from the start, note, velocity) per note-on."""
    clock = MonotonicClock()
    home = str(tmp / "home")
    fmt = p.PoseFormat.from_dtype(pose_dtype(len(load_kit("rock5").pieces)))
    procs = []
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    frames_dir = tmp / f"frames-{label}"
    try:
        inp = _spawn(["input", "--midi", "kit:pads", "--api", "jack", "--map", "roland-td",
                      "--pub", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*",
                      "--no-journal", *input_args], home, tmp / "input.err")  # fmt: skip
        procs.append(inp)
        in_ep = _line(inp)["pub"]
        syn = _spawn(["synth", "--sub", in_ep, "--pub", "tcp://127.0.0.1:*", "--control",
                      "tcp://127.0.0.1:*", "--delay-ms", str(delay_ms), "--lookahead-ms",
                      str(lookahead_ms), *synth_args], home, tmp / "synth.err")  # fmt: skip
        procs.append(syn)
        syn_ep = _line(syn)["pub"]
        disp = _spawn(["display", "--live", "--headless", "--sub", syn_ep, "--size", "320x180",
                       "--fps", "60", "--frames-dir", str(frames_dir), "--no-png",
                       *display_args], home, tmp / "display.err")  # fmt: skip
        procs.append(disp)
        _line(disp)
        ev = ctx.socket(zmq.SUB)
        ev.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
        ev.connect(in_ep)
        poses = ctx.socket(zmq.SUB)
        poses.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.POSE))
        poses.setsockopt(zmq.RCVHWM, 0)
        poses.connect(syn_ep)
        onsets: list[tuple[float, np.ndarray]] = []
        sent_by_daemon: list[float] = []  # header send time of each onset's message
        pose_in: list[tuple[float, np.ndarray]] = []

        def pump(seconds: float) -> None:
            end = clock.now() + seconds
            while True:
                left = end - clock.now()
                if left <= 0:
                    return
                for sock in zmq.select([ev, poses], [], [], min(left, 0.005))[0]:
                    msg = p.decode(sock.recv_multipart(), fmt)
                    if msg.kind is p.Kind.ONSET and isinstance(msg.body, np.ndarray):
                        onsets.append((clock.now(), msg.body.copy()))
                        sent_by_daemon.extend([msg.send_time_s] * msg.body.size)
                    elif isinstance(msg.body, p.Pose):
                        show = msg.body.time_s + msg.body.rows["time_s"].astype(np.float64)
                        pose_in.append((clock.now(), show))

        while not onsets:  # JACK and the subscriptions settle: probe until a note lands
            jack.out.send_message([0x99, 36, 1])
            pump(0.2)
        pump(1.0)
        onsets.clear()
        sent_by_daemon.clear()
        pose_in.clear()
        jack.loop_times.clear()
        sent: list[float] = []
        planned: list[float] = []
        stop = threading.Event()

        def play() -> None:
            start = clock.now() + 0.05
            for at, note, velocity in schedule:
                clock.wait_until(start + at, stop)
                planned.append(start + at)
                sent.append(clock.now())
                jack.out.send_message([0x99, note, velocity])

        player = threading.Thread(target=play)
        player.start()
        pump(schedule[-1][0] + 0.15)
        player.join()
        pump(2.0)
    finally:
        for proc in reversed(procs):
            proc.send_signal(signal.SIGTERM)
        for name, proc in zip(("input", "synth", "display"), procs, strict=False):
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                print(f"  ({name} did not stop on SIGTERM within 15 s: killed)")
                proc.kill()
                proc.wait()
        ctx.destroy(0)
    got_t = np.array([t for t, rows in onsets for _ in range(rows.size)])
    stamps = (
        np.concatenate([rows["time_s"] for _, rows in onsets]).astype(np.float64)
        if onsets
        else np.zeros(0)
    )
    n = min(len(sent), got_t.size)
    sent_a = np.array(sent[:n])
    loop = np.array(jack.loop_times[:n]) - sent_a[: len(jack.loop_times[:n])]
    bus = got_t[:n] - sent_a
    # pose: the first POSE message holding the contact sample at stamp + D
    d = delay_ms / 1000.0
    pose_lat, missing_pose = [], 0
    shows = [(t, s) for t, s in pose_in]
    contact_at = np.full(n, np.nan)
    for i in range(n):
        target = stamps[i] + d
        for t, s in shows:
            if (
                s.size
                and s[0] - 1e-6 <= target <= s[-1] + 1e-6
                and np.min(np.abs(s - target)) < 1e-6
            ):
                contact_at[i] = t
                break
        if np.isnan(contact_at[i]):
            missing_pose += 1
    pose_lat = (contact_at - sent_a)[~np.isnan(contact_at)]
    after_onset = (contact_at - stamps[:n])[~np.isnan(contact_at)]
    after_bus = (contact_at - got_t[:n])[~np.isnan(contact_at)]
    late_mask = contact_at - stamps[:n] > d
    # notes stamped within the sticking's chord window of the two before them, though planned
    # further apart: a third hand note "at once" that the sticking merges into a stroke
    plan = np.array(planned[:n])
    bunched = np.zeros(n, dtype=bool)
    if n > 2:
        bunched[2:] = (stamps[2:n] - stamps[: n - 2] <= CHORD_WINDOW_S) & (
            plan[2:] - plan[:-2] > CHORD_WINDOW_S
        )
    no_pose = np.isnan(contact_at)
    late = int(np.sum(late_mask))
    # Where the late ones are: how far past D, and in which quarter of the run (queueing
    # shows as lateness growing towards the end of a burst; a stray slow answer does not).
    over = (contact_at - stamps[:n] - d)[late_mask] * 1000.0
    quarter = np.minimum((4 * np.arange(n) // max(n, 1)), 3)[late_mask]
    late_where = (
        f"late by {np.percentile(over, 50):.1f} ms p50, {over.max():.1f} max; per quarter of "
        f"the run {np.bincount(quarter, minlength=4).tolist()}"
        if late
        else "none late"
    )
    frames = [json.loads(x) for x in (frames_dir / "frames.jsonl").read_text().splitlines()]
    drawn = [(f["pose_s"], f["done_s"]) for f in frames if f["pose_s"] is not None]
    frame_lat, frame_onset = [], []
    for i in range(n):
        target = stamps[i] + d
        done = next((ds for ps, ds in drawn if ps >= target - 1e-6), None)
        if done is not None:
            frame_lat.append(done - sent_a[i])
            frame_onset.append(done - stamps[i])
    return {
        "rate": label, "sent": len(sent), "on_bus": int(got_t.size), "loopback": loop,
        "bus": bus, "pose": np.asarray(pose_lat), "frame": np.asarray(frame_lat),
        "frame_onset": np.asarray(frame_onset),
        "after_onset": after_onset, "after_bus": after_bus, "late": late,
        "in_daemon": np.array(sent_by_daemon[:n]) - stamps[:n],
        "no_contact": missing_pose, "late_where": late_where,
        "sender_late": sent_a - plan, "bunched": int(bunched.sum()),
        "bunched_no_pose": int((bunched & no_pose).sum()),
        "synth": (tmp / "synth.err").read_text().strip()[-260:],
    }  # fmt: skip


def groove_schedule(seconds: float) -> list[tuple[float, int, int]]:
    """The demo groove's note-ons (GMD, Roland TD notes) in its first ``seconds``."""
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    from ..cli.files import demo_groove

    on = read_midi_file(demo_groove(), load_note_map("roland-td")).onsets
    on = on[on["time_s"] < seconds]
    t0 = float(on["time_s"][0])
    return [(float(r["time_s"]) - t0, int(r["note"]), max(1, int(r["velocity"]))) for r in on]


def _pct(a: np.ndarray) -> str:
    if a.size == 0:
        return "      -       -"
    return f"{np.percentile(a, 50) * 1000:7.2f} {np.percentile(a, 99) * 1000:7.2f}"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench latency", description=__doc__)
    parser.add_argument("--rates", type=float, nargs="+", default=[1.0, 100.0, 1000.0])
    parser.add_argument("--seconds", type=float, default=2.0, help="per rate (min 5 notes)")
    parser.add_argument(
        "--groove",
        type=float,
        default=0.0,
        metavar="S",
        help="also play the first S s of the demo groove as performed",
    )
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
    parser.add_argument(
        "--realtime",
        type=int,
        default=0,
        metavar="PRIO",
        help="input daemon at SCHED_FIFO PRIO (if permitted)",
    )
    parser.add_argument(
        "--no-render",
        action="store_true",
        help="the display logs frames without drawing them (the CPU a GPU "
        "would spare: llvmpipe draws on the pipeline's cores)",
    )
    parser.add_argument(
        "--no-provisional",
        action="store_true",
        help="the synth publishes a hit only once its hand is decided",
    )
    parser.add_argument(
        "--osc",
        action="store_true",
        help="synth and display read an OSC port too (show control on)",
    )
    parser.add_argument(
        "--overlay",
        metavar="LIST",
        help="the display draws these strips over every frame: score, joints (needs "
        "rendering; default none; score,joints with --both)",
    )
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        metavar="N",
        help="measure every rate N times (--both: median of medians)",
    )
    parser.add_argument(
        "--both",
        action="store_true",
        help="measure each rate twice: without and with show control (OSC "
        "ports and the strips), alternating, and compare the medians",
    )
    parser.add_argument(
        "--compare",
        metavar="REV",
        nargs="+",
        help="also run this bench from each commit REV (a temporary git "
        "worktree), alternating with this checkout, and print each beside "
        "it",
    )
    parser.add_argument(
        "--compare-runs",
        type=int,
        default=2,
        metavar="N",
        help="with --compare: runs of each commit (default 2)",
    )
    args = parser.parse_args(argv)
    if args.compare is not None:
        if CHECKOUT is None:
            parser.error("--compare needs a source checkout (git), not an installed wheel")
        if args.compare_runs < 1:
            parser.error(f"--compare-runs {args.compare_runs}: must be at least 1")
        return run_compare(CHECKOUT, args.compare, _without_compare(argv), args.compare_runs)
    if args.overlay:
        from livedrummer.render.overlay import parse_overlays

        parse_overlays(args.overlay)  # a typo is one line (exit 2), before JACK starts
    synth_args = ["--no-provisional"] if args.no_provisional else []
    osc = ["--osc", "0"]  # a port the system picks: polled, never sent to
    overlay = ["--overlay", args.overlay or "score,joints"]
    render = ["--no-render"] if args.no_render else []
    # (name, synth options, display options) of each way measured
    if args.both:
        modes = [("plain", synth_args, render), ("show", synth_args + osc, render + osc + overlay)]
    else:
        shown = (osc if args.osc else []) + (overlay if args.overlay else [])
        modes = [("", synth_args + (osc if args.osc else []), render + shown)]
    input_args = ["--realtime", str(args.realtime)] if args.realtime else []
    results: list[tuple[str, str, dict[str, Any]]] = []  # (mode, rate, run)
    jack = Jack()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            runs = [
                (
                    f"{rate:g}",
                    [
                        (i / rate, NOTES[i % 2], 64 + i % 60)
                        for i in range(max(5, int(rate * args.seconds)))
                    ],
                )
                for rate in args.rates
            ]
            if args.groove > 0:
                runs.append(("groove", groove_schedule(args.groove)))
            todo = [
                (rep + k, d, run)
                for rep in range(args.repeat)
                for k, (d, run) in enumerate((d, run) for d in args.delay_ms for run in runs)
            ]
            for flip, delay_ms, (label, schedule) in todo:  # each way first as often
                lookahead_ms = args.lookahead_ms or min(30.0, delay_ms)
                if label == runs[0][0]:
                    print(
                        f"D = {delay_ms:g} ms, L = {lookahead_ms:g} ms; ms from note-on "
                        f"sent, p50 p99; frame rendered within D + one frame at p99: "
                        f"<= {delay_ms + 1000 / 60:.1f} ms"
                    )
                    print(
                        f"{'notes/s':>8} {'sent':>5} {'bus':>5} {'no-pose':>7} {'late':>5} | "
                        f"{'JACK loop':>15} | {'onset on bus':>15} | {'pose at display':>15} | "
                        f"{'frame rendered':>15} | {'pose - onset':>15} | "
                        f"{'pose - bus':>15}"
                    )
                for mode, synth_mode, display_mode in modes if flip % 2 == 0 else modes[::-1]:
                    r = run_rate(
                        jack,
                        label,
                        schedule,
                        delay_ms,
                        lookahead_ms,
                        Path(tmp),
                        synth_mode,
                        input_args,
                        display_mode,
                    )
                    results.append((mode, f"{label} D={delay_ms:g}", r))
                    _print_run(r, label if not mode else f"{label} {mode}")
            if args.both:
                _print_both(results)
    finally:
        jack.close()
    return 0


def _without_compare(argv: list[str]) -> list[str]:
    """``argv`` less ``--compare REV [REV ...]`` and ``--compare-runs N`` (also as
    ``--opt=value``)."""
    out, skip = [], 0  # values still to skip (-1: every one up to the next option)
    for arg in argv:
        if skip and not (skip < 0 and arg.startswith("-")):
            skip -= skip > 0
        elif arg in ("--compare", "--compare-runs"):
            skip = -1 if arg == "--compare" else 1
        elif not arg.startswith(("--compare=", "--compare-runs=")):
            skip = 0
            out.append(arg)
    return out


def _print_run(r: dict[str, Any], label: str) -> None:
    """One pipeline's row and its detail line."""
    print(
        f"{label:>8} {r['sent']:5d} {r['on_bus']:5d} {r['no_contact']:7d} "
        f"{r['late']:5d} | {_pct(r['loopback'])} | {_pct(r['bus'])} | "
        f"{_pct(r['pose'])} | {_pct(r['frame'])} | "
        f"{_pct(r['after_onset'])} | {_pct(r['after_bus'])}",
        flush=True,
    )
    ab = r["after_bus"]
    fast = float(np.mean(ab <= 0.001)) if ab.size else 0.0
    print(
        f"         pose within 1 ms of the onset on the bus: {fast:.0%} of "
        f"contacts; frame - onset {_pct(r['frame_onset'])}; in the input daemon "
        f"(stamp -> sent) {_pct(r['in_daemon'])}; {_bunching(r)}{r['late_where']}; "
        f"{r['synth']}",
        flush=True,
    )


def _bunching(r: dict[str, Any]) -> str:
    """The detail line's part on the bench's sending and the notes stamped together (empty
    for a run that did not measure them)."""
    if "sender_late" not in r:
        return ""
    return (
        f"the bench's note-ons sent late {_pct(r['sender_late'])}; {r['bunched']} notes "
        f"stamped within {CHORD_WINDOW_S * 1000:g} ms of the two before them though sent "
        f"apart ({r['bunched_no_pose']} of them without a pose); "
    )


def _print_both(results: list[tuple[str, str, dict[str, Any]]]) -> None:
    """``--both``: the medians of each stage without and with show control, per rate (with
    ``--repeat``, the median of the runs' medians)."""
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"\nshow control off / on (OSC ports and the strips): medians in ms; load average "
        f"{load} (1, 5, 15 min)"
    )
    stages = (
        ("bus", "onset on bus"),
        ("pose", "pose at display"),
        ("frame", "frame rendered"),
        ("frame_onset", "frame - onset"),
        ("after_onset", "pose - onset"),
    )
    print(f"{'run':>14} | " + " | ".join(f"{name:>21}" for _, name in stages))
    for run in dict.fromkeys(label for _, label, _ in results):
        cells = []
        for key, _ in stages:
            med = [
                float(
                    np.median(
                        [
                            np.median(r[key])
                            for m, label, r in results
                            if m == mode and label == run and r[key].size
                        ]
                        or [np.nan]
                    )
                )
                * 1000
                for mode in ("plain", "show")
            ]
            cells.append(f"{med[0]:6.2f} / {med[1]:6.2f} ({med[1] - med[0]:+5.2f})")
        print(f"{run:>14} | " + " | ".join(cells), flush=True)
