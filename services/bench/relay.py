"""Fan-out through ``livedrummer relay``: 1 pose publisher → relay → N display subscribers.

The publisher (this process) sends real POSE messages (the rock5 pose dtype, ``--samples``
rows each, as the synth's 120 Hz ticks carry at 240 samples/s) at ``--rate`` messages per
second for ``--seconds``; N SUB sockets (``--displays``, default 50: headless displays that do
not draw, all in one subscriber thread) receive them, first straight from the publisher, then
through a relay started as its own process (the real CLI). Per run: messages delivered (every
subscriber must hold every message), latency from the header's send time to receipt on the
shared clock (p50/p99 over all subscribers and messages), the relay's CPU share from
``/proc`` and its output rate. The difference of the two runs' latencies is what one relay
hop adds; the last lines turn it into the arithmetic of a tree of relays. The subscriber
thread reads its N sockets in turn, so both runs carry the same queueing of 50 readers.

Figures from one run on whatever the machine is doing; no assertions.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.kit.loader import load_kit
from livedrummer.timeline.clock import MonotonicClock

from ..process.program import program_argv
from ._paths import WORKDIR

CLK_TCK = os.sysconf("SC_CLK_TCK")


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime + stime


def _run(
    endpoint: str,
    n_subs: int,
    send: threading.Event,
    done: threading.Event,
    ctx: zmq.Context[zmq.Socket[bytes]],
    fmt: p.PoseFormat,
    out: list[list[float]],
) -> None:
    """Subscriber thread: N SUB sockets, every receipt's latency (s) per socket."""
    clock = MonotonicClock()
    socks = []
    poller = zmq.Poller()
    for _ in range(n_subs):
        s = ctx.socket(zmq.SUB)
        s.setsockopt(zmq.LINGER, 0)
        s.setsockopt(zmq.RCVHWM, 100_000)
        s.setsockopt(zmq.SUBSCRIBE, p.MAGIC)
        s.connect(endpoint)
        socks.append(s)
        poller.register(s, zmq.POLLIN)
        out.append([])
    index = {s: k for k, s in enumerate(socks)}
    send.set()
    quiet_since = math.inf
    while True:
        events = poller.poll(50)
        now = clock.now()
        for s, _ in events:
            while True:
                try:
                    frames = s.recv_multipart(zmq.NOBLOCK)
                except zmq.Again:
                    break
                msg = p.decode(frames, fmt)
                if msg.kind is p.Kind.POSE:
                    out[index[s]].append(now - msg.send_time_s)
        if done.is_set():
            quiet_since = min(quiet_since, now) if not events else math.inf
            if now - quiet_since > 0.5:
                break
    for s in socks:
        s.close(0)


def _measure(
    pub: zmq.Socket[bytes],
    endpoint: str,
    args: argparse.Namespace,
    fmt: p.PoseFormat,
    rows: np.ndarray,
) -> list[list[float]]:
    clock = MonotonicClock()
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()  # the displays' own I/O thread
    send, done = threading.Event(), threading.Event()
    lat: list[list[float]] = []
    t = threading.Thread(target=_run, args=(endpoint, args.displays, send, done, ctx, fmt, lat))
    t.start()
    send.wait()
    time.sleep(args.settle)  # the subscriptions reach the publisher (through the relay)
    period = 1.0 / args.rate
    next_s = clock.now()
    for seq in range(round(args.seconds * args.rate)):
        while clock.now() < next_s:
            time.sleep(max(0.0, min(0.001, next_s - clock.now())))
        now = clock.now()
        msg = p.Message(p.Kind.POSE, p.Pose(now, rows), 0, seq, now, p.Stream.POSES)
        pub.send_multipart(p.encode(msg, fmt))
        next_s += period
    done.set()
    t.join()
    ctx.term()
    return lat


def _report(name: str, lat: list[list[float]], sent: int) -> tuple[float, float]:
    got = [len(x) for x in lat]
    flat = np.concatenate([np.asarray(x) for x in lat]) * 1000 if any(got) else np.zeros(1)
    p50, p99 = (float(v) for v in np.percentile(flat, [50, 99]))
    print(
        f"{name:>8}: {sum(got):,} of {sent * len(lat):,} delivered (fewest to one display "
        f"{min(got):,} of {sent:,}); latency p50 {p50:.2f} ms, p99 {p99:.2f} ms"
    )
    return p50, p99


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="livedrummer bench relay", description=__doc__)
    ap.add_argument("--displays", type=int, default=50, help="subscribers (default 50)")
    ap.add_argument("--rate", type=float, default=120.0, help="messages/s (default 120)")
    ap.add_argument("--samples", type=int, default=2, help="pose rows a message (default 2)")
    ap.add_argument("--seconds", type=float, default=10.0, help="each run (default 10)")
    ap.add_argument("--settle", type=float, default=1.0, help="wait for subscriptions (s)")
    args = ap.parse_args(argv)
    kit = load_kit("rock5")
    fmt = p.PoseFormat.from_dtype(pose_dtype(len(kit.pieces)))
    rows = np.zeros(args.samples, pose_dtype(len(kit.pieces)))
    sent = round(args.seconds * args.rate)
    size = len(
        b"".join(
            p.encode(p.Message(p.Kind.POSE, p.Pose(0.0, rows), 0, 0, 0.0, p.Stream.POSES), fmt)
        )
    )
    print(
        f"bench relay: {args.displays} displays, {args.rate:g} pose messages/s of {size:,} "
        f"bytes ({args.samples} samples), {args.seconds:g} s a run"
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()  # the publisher's I/O thread
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    pub.setsockopt(zmq.SNDHWM, 100_000)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    upstream = f"tcp://127.0.0.1:{port}"
    _measure(pub, upstream, args, fmt, rows)  # warm-up: first connections, caches
    direct = _measure(pub, upstream, args, fmt, rows)
    with tempfile.TemporaryDirectory() as home:
        relay = subprocess.Popen(
            [
                *program_argv(),
                "relay",
                "--upstream",
                upstream,
                "--pub",
                "tcp://127.0.0.1:*",
                "--control",
                "tcp://127.0.0.1:*",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            cwd=WORKDIR,
            env={**os.environ, "LIVEDRUMMER_HOME": home},
        )
        try:
            assert relay.stdout is not None
            eps = json.loads(relay.stdout.readline())
            cpu0, wall0 = _cpu_s(relay.pid), time.monotonic()
            via = _measure(pub, eps["pub"], args, fmt, rows)
            cpu = (_cpu_s(relay.pid) - cpu0) / (time.monotonic() - wall0)
        finally:
            relay.send_signal(signal.SIGTERM)
            relay.wait(10)
    d50, d99 = _report("direct", direct, sent)
    r50, r99 = _report("relay", via, sent)
    out_mbit = size * args.rate * args.displays * 8 / 1e6
    print(f"   relay: {100 * cpu:.1f} % of one core while forwarding, {out_mbit:.2f} Mbit/s out")
    a50, a99 = r50 - d50, r99 - d99
    print(
        f"   relay minus direct: p50 {a50:+.2f} ms, p99 {a99:+.2f} ms (negative: serving "
        f"{args.displays} sockets costs the publisher more than the hop costs)"
    )
    a99 = max(a99, r99)  # the tree's bound: a hop's whole p99, not the difference
    for depth in (1, 2, 3):
        fan = args.displays
        relays = (fan**depth - 1) // max(fan - 1, 1)
        print(
            f"   tree of depth {depth}, {fan} per relay: {fan**depth:,} displays, {relays:,} "
            f"relays, +{depth * a99:.1f} ms p99 (hops add up), {out_mbit:.2f} Mbit/s out of "
            "each relay"
        )
    pub.close(0)
    ctx.term()
    sys.stdout.flush()
    return 0
