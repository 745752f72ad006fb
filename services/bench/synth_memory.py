"""Synth memory on a long show: 500,000 onsets through a running synth, its RSS as it goes.

The synth must not grow with the number of notes played (a show runs for hours). This
benchmark starts the real service (``python -m livedrummer synth``, its own process, on
OS-chosen loopback ports) and plays the input daemon's part itself: a ZeroMQ PUB socket
sending ONSET messages (one onset each, stamped with the shared clock at sending, as the
daemon stamps arrivals), a CC4 hi-hat pedal CONTROL every ten onsets and a crash choke (grab
and release) every two thousand, all with consecutive sequence numbers. The notes cycle
through the bundled GMD groove (its instruments, zones, velocities), so the sticking, the
quick contacts and the re-animations do their usual work, only faster.

Rate: as fast as the synth takes them. The sender paces itself (``--rate``, notes/s, the
start) and watches the synth's pose stream: each batch of quick contacts shows the onset it
answers at onset + D, so ``now - (newest show time - D)`` is how far the synth is behind; its
least value within a second is the synth's backlog (a re-animation's step may hold answers
back for a moment without the synth falling behind). When the backlog passes
``--max-lag-ms`` (1 s) the rate drops by a fifth; when it stays under a quarter of it the
rate rises by a twentieth (up to ``--max-rate``). The
sender's queue is unbounded (SNDHWM 0), so nothing is dropped on the way: the synth's own
count of onsets and of messages lost upstream (its exit summary) is printed beside what was
sent (the synth counts from the first message it heard: a probe sent before its SUB socket
had connected is neither counted nor lost).

RSS (``VmRSS`` of the synth's process, ``/proc``) is read at checkpoints (10k, 50k, 100k,
200k, 300k, 400k, 500k onsets sent), each once the synth has answered the last onset sent (at
most 30 s) and 0.2 s more, so no backlog is counted; the figure is RSS(500k) - RSS(50k)
(goal: under 5 MB). Figures only; no assertions. Limits: at flood rates the synth spends its
time on quick contacts and the online sticking's chords (hundreds of notes a second fall in
one 15 ms chord window), so the rate it takes on a shared 2-core machine is some hundreds of
notes a second, and 500,000 onsets take a quarter of an hour or more there.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.resources import data_dir
from livedrummer.timeline.clock import MonotonicClock
from livedrummer.timeline.events import CONTROL_DTYPE, ControlKind

from ..process.program import program_argv
from ._paths import WORKDIR

REPO = WORKDIR  # child processes start in the checkout (or the user's folder)
GROOVE = data_dir("kits") / "grooves" / "gmd-drummer1-funk-80.mid"
CHECKPOINTS = (10_000, 50_000, 100_000, 200_000, 300_000, 400_000, 500_000)
DELAY_S = 0.030  # the synth's default D
CRASH_NOTE = 49  # roland-td crash 1
MIN_RATE = 100.0  # notes/s: the sender never goes slower


def rss_kb(pid: int, field_name: str = "VmRSS") -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith(field_name + ":"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


@dataclass
class Feed:
    sent: int = 0  # onsets
    controls: int = 0
    seq: int = 0
    lags_s: list[float] = field(default_factory=list)  # per second: the largest lag seen
    rates: list[float] = field(default_factory=list)  # per second: the rate asked for
    pose_messages: int = 0
    rss_kb: dict[int, int] = field(default_factory=dict)
    send_s: float = 0.0  # time spent sending (pauses left out)


class Synth:
    """The synth service as a child process, with its endpoints."""

    def __init__(self, sub: str, home: Path) -> None:
        env = {**os.environ, "LIVEDRUMMER_HOME": str(home)}
        self.proc = subprocess.Popen(
            [
                *program_argv(),
                "synth",
                "--sub",
                sub,
                "--pub",
                "tcp://127.0.0.1:*",
                "--control",
                "tcp://127.0.0.1:*",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            cwd=REPO,
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            err = self.proc.stderr.read() if self.proc.stderr is not None else ""
            raise SystemExit(f"synth_memory: the synth did not start: {err[-2000:]}")
        self.endpoints: dict[str, str] = json.loads(line)

    def stop(self) -> str:
        self.proc.send_signal(signal.SIGTERM)
        try:
            _, err = self.proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err


def groove_rows() -> np.ndarray:
    perf = read_midi_file(GROOVE, load_note_map("roland-td"))
    return perf.onsets.copy()


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="livedrummer bench synth_memory", description=__doc__)
    ap.add_argument("--onsets", type=int, default=500_000, help="onsets to send (default 500000)")
    ap.add_argument("--rate", type=float, default=600.0, help="starting rate, notes/s (600)")
    ap.add_argument("--max-rate", type=float, default=3000.0, help="highest rate (3000)")
    ap.add_argument(
        "--max-lag-ms",
        type=float,
        default=1000.0,
        help="synth lag allowed before the rate drops (1000)",
    )
    ap.add_argument("--verbose", action="store_true", help="the rate and lag every second")
    args = ap.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # the synth is stopped on the way
    checkpoints = sorted({c for c in CHECKPOINTS if c < args.onsets} | {args.onsets})
    clock = MonotonicClock()
    fmt = p.PoseFormat.from_dtype(pose_dtype(len(load_kit("rock5").pieces)))
    notes = groove_rows()
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    pub.setsockopt(zmq.SNDHWM, 0)  # never drop: a slow synth makes the sender's queue grow
    pub.bind("tcp://127.0.0.1:*")
    sub_ep = pub.getsockopt(zmq.LAST_ENDPOINT).decode()  # type: ignore[union-attr]
    feed = Feed()
    with tempfile.TemporaryDirectory(prefix="ld-synthmem-") as tmp:
        synth = Synth(sub_ep, Path(tmp))
        try:
            poses = ctx.socket(zmq.SUB)
            poses.setsockopt(zmq.LINGER, 0)
            poses.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.POSE))
            poses.connect(synth.endpoints["pub"])
            newest = [-np.inf]  # newest show time published (a tick: now + D; quick: onset + D)
            lit = [False]  # a hit came back (the synth's SUB is connected)

            def drain() -> None:
                while True:
                    try:
                        frames = poses.recv_multipart(zmq.NOBLOCK)
                    except zmq.Again:
                        return
                    msg = p.decode(frames, fmt)
                    feed.pose_messages += 1
                    if isinstance(msg.body, p.Pose) and msg.body.rows.size:
                        rows = msg.body.rows
                        show = msg.body.time_s + float(rows["time_s"][-1])
                        newest[0] = max(newest[0], show)
                        lit[0] = lit[0] or bool(rows["glow"].max() > 0)

            def send(kind: p.Kind, rows: np.ndarray) -> None:
                msg = p.Message(kind, rows, 0, feed.seq, clock.now(), p.Stream.EVENTS)
                pub.send_multipart(p.encode(msg), copy=False)
                feed.seq += 1

            last_sent = [-np.inf]  # the newest onset's stamp

            def onset(k: int) -> None:
                row = notes[k % notes.size : k % notes.size + 1].copy()
                row["time_s"] = last_sent[0] = clock.now()
                send(p.Kind.ONSET, row)

            def control(kind: ControlKind, number: int, value: int) -> None:
                row = np.zeros(1, CONTROL_DTYPE)
                row["time_s"], row["kind"], row["channel"] = clock.now(), kind, 9
                row["number"], row["value"] = number, value
                send(p.Kind.CONTROL, row)
                feed.controls += 1

            # the synth's SUB connects asynchronously: probe until a hit comes back lit
            deadline = clock.now() + 30
            while not lit[0] and clock.now() < deadline:
                onset(feed.sent)
                feed.sent += 1
                for _ in range(10):
                    time.sleep(0.01)
                    drain()
            if not lit[0]:
                print("synth_memory: the synth never answered a hit", file=sys.stderr)
                synth.stop()
                return 1
            pid = synth.proc.pid
            rss_start = rss_kb(pid)
            rate = args.rate
            t_sec = clock.now()
            lag_sec = np.inf
            start = clock.now()
            next_send = start
            paused = 0.0
            for cp in checkpoints:
                while feed.sent < cp:
                    now = clock.now()
                    if now >= next_send:
                        k = feed.sent
                        onset(k)
                        feed.sent += 1
                        if k % 10 == 0:
                            control(ControlKind.HIHAT_PEDAL, 4, (k // 10) % 128)
                        if k % 2000 == 1000:
                            control(ControlKind.CHOKE, CRASH_NOTE, 127)
                        if k % 2000 == 1200:
                            control(ControlKind.CHOKE, CRASH_NOTE, 0)
                        next_send = max(next_send + 1.0 / rate, now - 0.01)
                    drain()
                    now = clock.now()
                    # the least lag within a second: the synth's backlog (a re-animation's step
                    # may hold back its answers for a moment without it falling behind)
                    lag_sec = min(lag_sec, now - (newest[0] - DELAY_S))
                    if now - t_sec >= 1.0:
                        feed.lags_s.append(lag_sec)
                        feed.rates.append(rate)
                        if args.verbose:
                            print(
                                f"    {feed.sent:>7,} sent, rate {rate:,.0f}/s, synth behind by "
                                f"at least {lag_sec * 1000:,.0f} ms",
                                flush=True,
                            )
                        if lag_sec > args.max_lag_ms / 1000:
                            rate = max(MIN_RATE, rate * 0.8)
                        elif lag_sec < args.max_lag_ms / 4000:
                            rate = min(args.max_rate, rate * 1.05)
                        t_sec, lag_sec = now, np.inf
                    wait = next_send - clock.now()
                    if wait > 0.0005:
                        poses.poll(max(0, int(wait * 1000)))
                pause_at = clock.now()  # until the synth has caught up (at most 30 s), then 0.2 s
                while clock.now() - pause_at < 30 and newest[0] - DELAY_S < last_sent[0]:
                    poses.poll(20)
                    drain()
                caught_up = clock.now()
                while clock.now() - caught_up < 0.2:
                    poses.poll(20)
                    drain()
                feed.rss_kb[cp] = rss_kb(pid)
                paused += clock.now() - pause_at
                next_send = clock.now()
                t_sec, lag_sec = clock.now(), np.inf
                print(
                    f"  {cp:>7,} onsets sent: synth RSS {feed.rss_kb[cp] / 1024:7.1f} MiB "
                    f"(rate now {rate:,.0f}/s, {clock.now() - start:6.1f} s)",
                    flush=True,
                )
            feed.send_s = clock.now() - start - paused
            hwm = rss_kb(pid, "VmHWM")
            err = synth.stop()
        finally:
            if synth.proc.poll() is None:
                synth.proc.kill()
        poses.close(0)
    pub.close(0)
    ctx.term()
    summary = next((ln for ln in err.splitlines() if ln.startswith("synth:")), err[-500:])
    lags = np.array(feed.lags_s) * 1000
    print(
        f"synth_memory: {feed.sent:,} onsets and {feed.controls:,} controls sent in "
        f"{feed.send_s:.1f} s ({feed.sent / feed.send_s:,.0f} onsets/s on average; the rate "
        f"asked for ended at {feed.rates[-1] if feed.rates else args.rate:,.0f}/s)"
    )
    if lags.size:
        print(
            f"  synth's backlog (least lag within each second): p50 "
            f"{np.percentile(lags, 50):.0f} ms, max {lags.max():.0f} ms"
        )
    print(f"  the synth says: {summary}")
    print(f"  RSS at start {rss_start / 1024:.1f} MiB, peak {hwm / 1024:.1f} MiB")
    first = 50_000 if 50_000 in feed.rss_kb else checkpoints[0]
    last = checkpoints[-1]
    growth = (feed.rss_kb[last] - feed.rss_kb[first]) / 1024
    print(
        f"  RSS at {first:,}: {feed.rss_kb[first] / 1024:.1f} MiB; at {last:,}: "
        f"{feed.rss_kb[last] / 1024:.1f} MiB; growth {growth:+.2f} MiB "
        "(goal < 5 MB)"
    )
    return 0
