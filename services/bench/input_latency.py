"""Input latency benchmark: a note sent by the "kit" → onset received on the bus.

Runs the real daemon (``livedrummer input``) as a subprocess and plays note-ons into it at 1,
100 and 1,000 notes/s (configurable) from either end of a serial pseudo-terminal
(``--source pty``, default) or a virtual JACK MIDI port on a ``jackd -d dummy`` server started
for the run (``--source jack``; needs Debian jackd2). It subscribes to the daemon's events.
Every time is read on the shared clock, so four intervals are measured per note: sent →
arrival stamp (pty or JACK + rtmidi), arrival stamp → publish (the daemon: decode, journal
write, encode; the header's send time), publish → received (ZeroMQ over loopback TCP and the
subscriber's decode), and sent → received.
Prints p50/p99/max per rate and the notes lost before the journal and after it (should be 0; the
journal tells where). Figures only, no assertions.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.protocol.journal import read_journal
from livedrummer.timeline.clock import MonotonicClock

from ..process.program import program_argv
from ._paths import WORKDIR

REPO = WORKDIR  # child processes start in the checkout (or the user's folder)


Send = Callable[[bytes], None]


#: (note, velocity) of the i-th note: unique over 127 * len(NOTES) notes, so a lost note is
#: recognised and the pairing of sent and received times stays right after it.
NOTES = (36, 37, 38, 40, 43, 45, 47, 48, 50, 58, 49, 51)  # all in the roland-td map


def key(i: int) -> tuple[int, int]:
    return NOTES[(i // 127) % len(NOTES)], 1 + i % 127


def _writer(send: Send, rate: float, count: int, sent: list[float], clock: MonotonicClock) -> None:
    cancel = threading.Event()
    start = clock.now() + 0.05
    for i in range(count):
        clock.wait_until(start + i / rate, cancel)
        sent.append(clock.now())
        send(bytes((0x99, *key(i))))


class PtyKit:
    def __init__(self) -> None:
        self.master, slave = os.openpty()
        self.args = ["--serial", os.ttyname(slave), "--baud", "115200"]
        os.close(slave)
        self.env: dict[str, str] = {}

    def send(self, data: bytes) -> None:
        os.write(self.master, data)

    def close(self) -> None:
        os.close(self.master)


class JackKit:
    def __init__(self) -> None:
        import rtmidi

        name = f"ldbench-{os.getpid()}"
        self.env = {"JACK_DEFAULT_SERVER": name, "JACK_NO_AUDIO_RESERVATION": "1"}
        os.environ.update(self.env)
        self.jackd = subprocess.Popen(
            ["jackd", "--no-realtime", "-S", "-n", name, "-d", "dummy", "-r", "48000", "-p", "64"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        subprocess.run(["jack_wait", "-s", name, "-w", "-t", "10"], check=True, capture_output=True)
        self.out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
        self.out.open_virtual_port("pads")
        self.args = ["--midi", "kit:pads", "--api", "jack"]

    def send(self, data: bytes) -> None:
        self.out.send_message(data)

    def close(self) -> None:
        self.out.close_port()
        self.jackd.terminate()
        self.jackd.wait(10)


def run_rate(rate: float, seconds: float, kit: PtyKit | JackKit, home: str) -> dict[str, Any]:
    clock = MonotonicClock()
    count = max(5, int(rate * seconds))
    proc = subprocess.Popen(
        [
            *program_argv(),
            "input",
            *kit.args,
            "--map",
            "roland-td",
            "--pub",
            "tcp://127.0.0.1:*",
            "--control",
            "tcp://127.0.0.1:*",
            "--wait-subscribers",
            "1",
            "--fsync-interval",
            "1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        cwd=REPO,
        env={**os.environ, **kit.env, "LIVEDRUMMER_HOME": home},
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
    stamps: list[float] = []
    published: list[float] = []
    received: list[float] = []
    keys: list[tuple[int, int]] = []
    sent: list[float] = []
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        sub.connect(info["pub"])
        # Subscription reaches the daemon asynchronously; a HELLO round trip after connecting
        # does not prove it, so probe with a note until one is received.
        probe_deadline = clock.now() + 10
        while clock.now() < probe_deadline:
            kit.send(bytes((0x99, 36, 1)))
            if sub.poll(100):
                sub.recv_multipart()
                break
        while sub.poll(200):
            sub.recv_multipart()
        writer = threading.Thread(target=_writer, args=(kit.send, rate, count, sent, clock))
        writer.start()
        deadline = clock.now() + count / rate + 5
        while len(stamps) < count and clock.now() < deadline:
            if not sub.poll(100):
                continue
            frames = sub.recv_multipart()
            now = clock.now()
            msg = p.decode(frames)
            for t, note, vel in msg.rows[["time_s", "note", "velocity"]].tolist():
                stamps.append(t)
                published.append(msg.send_time_s)
                received.append(now)
                keys.append((note, vel))
        writer.join()
    finally:
        proc.terminate()
        proc.wait(10)
        sub.close(0)
        ctx.term()
    journaled = 0
    for path in Path(home).glob("sessions/*.ldj"):
        onsets = read_journal(path.read_bytes(), str(path)).onsets
        journaled += int((onsets["time_s"] >= sent[0]).sum()) if sent else 0
    pairs = []  # (sent index, received index), skipping lost notes
    i = 0
    for j, k in enumerate(keys):
        while i < len(sent) and key(i) != k:
            i += 1
        if i < len(sent):
            pairs.append((i, j))
            i += 1
    si = [a for a, _ in pairs]
    rj = [b for _, b in pairs]
    s = np.array(sent)[si] if pairs else np.zeros(0)
    a, pub, r = (np.array(x)[rj] if pairs else np.zeros(0) for x in (stamps, published, received))
    return {
        "rate": rate,
        "sent": len(sent),
        "received": len(pairs),
        "journaled": journaled,
        "sent→stamp": (a - s) * 1e3,
        "stamp→publish": (pub - a) * 1e3,
        "publish→recv": (r - pub) * 1e3,
        "sent→recv": (r - s) * 1e3,
    }


def _fmt(x: np.ndarray) -> str:
    if not x.size:
        return "n/a"
    p50, p99 = np.percentile(x, [50, 99])
    return f"{p50:6.3f} / {p99:6.3f} / {x.max():6.3f}"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench input_latency")
    parser.add_argument("--rates", default="1,100,1000", help="notes per second, comma-separated")
    parser.add_argument("--seconds", type=float, default=5.0, help="seconds per rate")
    parser.add_argument("--source", choices=("pty", "jack"), default="pty")
    args = parser.parse_args(argv)
    rates = [float(r) for r in args.rates.split(",")]
    print(f"input latency, {args.source} → daemon → loopback TCP, ms (p50 / p99 / max)")
    print("lost: before the journal (device, driver, daemon) / after it (bus, subscriber)")
    columns = ("sent→stamp", "stamp→publish", "publish→recv", "sent→recv")
    print(f"{'notes/s':>8} {'sent':>6} {'lost':>11}" + "".join(f"  {c:>24}" for c in columns))
    for rate in rates:
        kit = PtyKit() if args.source == "pty" else JackKit()
        try:
            with tempfile.TemporaryDirectory() as home:
                r = run_rate(rate, args.seconds, kit, home)
        finally:
            kit.close()
        print(
            f"{rate:>8g} {r['sent']:>6} {r['sent'] - r['journaled']:>5} "
            f"{r['journaled'] - r['received']:>5}" + "".join(f"  {_fmt(r[c]):>24}" for c in columns)
        )
    return 0
