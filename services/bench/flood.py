"""Flood benchmark: 10,000 notes/s for 10 s into the input daemon, then how fast it recovers.

Source: a serial pseudo-terminal fed raw MIDI bytes (``livedrummer input --serial PTY``), the
daemon's real serial path (pyserial, the running-status parser, the shared decoder, journal,
ZeroMQ). A pty is chosen over the JACK MIDI path because it is not limited by a baud rate or
by JACK's per-cycle MIDI buffer (so 10,000 notes/s really arrive; a real trigger board at
31,250 baud cannot send more than ~1,000), and it is exact on a loaded 2-core machine, where
a JACK2 client that misses its cycle loses MIDI (see :mod:`services.input.midiport`). A pty
master blocks the writer when the daemon falls behind (the kernel's buffer is the only queue
before the daemon), so the rate actually achieved is measured and printed.

Phases, all times on the shared clock (:mod:`livedrummer.timeline.clock`): a baseline of single
probe notes at ``--probe-rate`` (10/s) gives the normal send → onset-on-the-bus latency; the flood
(notes spread evenly, written every millisecond); then probes again from the flood's last
byte on. Recovery time is when the first probe is sent whose latency is back within the
baseline median + tolerance (``max(1 ms, median)``), measured from the flood's last byte
(resolution: the probe period); how many later probes still exceed it is printed beside the
same count for the baseline, since a shared machine has outliers in both. The drain time is
when the subscriber received the flood's last onset. While flooding, every 50 ms: the daemon's
RSS (``/proc/PID/status``), the bytes waiting in the pty (``FIONREAD``) and the notes in
flight (sent, not yet received). A subscriber counts every onset and checks the sequence
numbers; after the daemon stopped, its journal is read and its onsets counted.

Figures only, no assertions (``tests/services/bench/test_flood.py`` asserts on counts and bounds).
"""

from __future__ import annotations

import argparse
import fcntl
import json
import logging
import os
import signal
import struct
import subprocess
import tempfile
import termios
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.timeline.clock import MonotonicClock

from ..input.journal import load_journal
from ..process.program import program_argv
from ..wire.stream_rx import StreamReceiver
from ._paths import WORKDIR

REPO = WORKDIR  # child processes start in the checkout (or the user's folder)
PROBE_NOTE = 36  # kick: probes only; the flood never plays it
FLOOD_NOTES = (37, 38, 40, 43, 45, 47, 48, 50, 58, 49, 51)  # all in the roland-td map
SAMPLE_S = 0.05


@dataclass
class FloodResult:
    rate: float  # notes/s asked for
    seconds: float
    sent: int = 0  # flood notes written to the pty
    achieved_rate: float = 0.0  # notes/s actually written (the pty blocks a slow reader)
    received: int = 0  # flood onsets a subscriber received
    journaled: int = 0  # flood onsets in the journal
    seq_missing: int = 0  # messages the subscriber saw missing (sequence gaps)
    gap_messages: int = 0  # GAP messages published (the daemon says it shed events)
    journal_clean: bool = False
    daemon_exit: int | None = None
    alive_after: bool = False  # the daemon was still running after the flood and the probes
    rss_before_kb: int = 0
    rss_max_kb: int = 0
    rss_after_kb: int = 0
    pty_backlog_max: int = 0  # bytes
    in_flight_max: int = 0  # flood notes sent, not yet received
    baseline_ms: list[float] = field(default_factory=list)
    probes_ms: list[float] = field(default_factory=list)  # after the flood, in order
    probe_offsets_s: list[float] = field(default_factory=list)  # probe send - flood end
    drain_s: float = float("nan")  # flood end → last flood onset received
    recovery_s: float = float("nan")
    threshold_ms: float = 0.0
    stderr_tail: str = ""


def rss_kb(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


def pty_backlog(fd: int) -> int:
    buf = fcntl.ioctl(fd, termios.FIONREAD, b"\0\0\0\0")
    return int(struct.unpack("i", buf)[0])


class Listener:
    """Subscriber thread: every message, sequence numbers, flood onset count, probe times."""

    def __init__(self, ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str) -> None:
        self.rx = StreamReceiver(
            "flood listener", logging.getLogger("livedrummer.bench"), list(p.Kind)
        )
        self.rx.connect(ctx, endpoint, "flood listener", hwm=0)
        self.clock = MonotonicClock()
        self.flood = 0
        self.last_flood_s = float("nan")
        self.probes: dict[int, float] = {}  # probe velocity -> received time (latest)
        self.gaps = 0
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, name="flood-listener", daemon=True)

    def _run(self) -> None:
        rx = self.rx
        while not self.stop.is_set():
            if not rx.poll(50):
                continue
            batch = rx.drain(16)  # small batches: one arrival time stands for 16 at most
            now = self.clock.now()
            for msg in batch.messages:
                if msg.kind is p.Kind.GAP:
                    self.gaps += 1
                if msg.kind is not p.Kind.ONSET:
                    continue
                notes = msg.rows["note"]
                probe = notes == PROBE_NOTE
                n = int(notes.size - probe.sum())
                if n:
                    self.flood += n
                    self.last_flood_s = now
                for vel in msg.rows["velocity"][probe].tolist():
                    self.probes[vel] = now

    def missing(self) -> int:
        return self.rx.counts.missing


def probe(master: int, listener: Listener, clock: MonotonicClock, k: int) -> float:
    """Send probe ``k`` and wait (≤ 2 s) for its onset; latency in ms (nan if lost)."""
    vel = 1 + k % 127
    listener.probes.pop(vel, None)
    sent = clock.now()
    os.write(master, bytes((0x99, PROBE_NOTE, vel)))
    deadline = sent + 2.0
    while vel not in listener.probes and clock.now() < deadline:
        time.sleep(0.0002)
    got = listener.probes.get(vel)
    return float("nan") if got is None else (got - sent) * 1e3


def probes_at(
    master: int, listener: Listener, clock: MonotonicClock, rate: float, count: int, first: int
) -> tuple[list[float], list[float]]:
    """``count`` probes at ``rate``/s from now: (send times, latencies in ms)."""
    start = clock.now()
    cancel = threading.Event()
    times, lat = [], []
    for i in range(count):
        clock.wait_until(start + i / rate, cancel)
        times.append(clock.now())
        lat.append(probe(master, listener, clock, first + i))
    return times, lat


def flood_writer(
    master: int, rate: float, seconds: float, clock: MonotonicClock, progress: list[int]
) -> float:
    """Write ``rate * seconds`` notes evenly, a chunk per millisecond, counting them in
    ``progress[0]``; return the time the last byte was written."""
    total = int(rate * seconds)
    chunk = bytearray()
    start = clock.now()
    end = start
    while progress[0] < total:
        sent = progress[0]
        due = min(total, int((clock.now() - start) * rate) + 1)
        if due > sent:
            chunk.clear()
            for i in range(sent, due):
                chunk += bytes((0x99, FLOOD_NOTES[i % len(FLOOD_NOTES)], 1 + (i // 11) % 127))
            os.write(master, chunk)  # blocks while the pty is full: the daemon is behind
            end = clock.now()
            progress[0] = due
        time.sleep(0.001)
    return end


def run_flood(
    rate: float,
    seconds: float,
    home: Path,
    probe_rate: float = 10.0,
    baseline: int = 20,
    after_s: float = 3.0,
) -> FloodResult:
    """One flood run against a fresh daemon subprocess; see the module docstring."""
    clock = MonotonicClock()
    result = FloodResult(rate, seconds)
    master, slave = os.openpty()
    tty = os.ttyname(slave)
    err_path = home / "input.err"
    proc = subprocess.Popen(
        [
            *program_argv(),
            "input",
            "--serial",
            tty,
            "--baud",
            "115200",
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
        stderr=err_path.open("w"),
        text=True,
        cwd=REPO,
        env={**os.environ, "LIVEDRUMMER_HOME": str(home)},
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    listener: Listener | None = None
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"the input daemon did not start: {err_path.read_text()[-800:]}")
        info = json.loads(line)
        listener = Listener(ctx, info["pub"])
        listener.thread.start()
        k = 0
        deadline = clock.now() + 10
        while not listener.probes and clock.now() < deadline:  # subscription and pty settled
            probe(master, listener, clock, k)
            k += 1
        time.sleep(0.2)
        _, result.baseline_ms = probes_at(master, listener, clock, probe_rate, baseline, k)
        k += baseline
        result.rss_before_kb = rss_kb(proc.pid)
        done = threading.Event()
        progress = [0]
        out: dict[str, float] = {}

        def write() -> None:
            out["end"] = flood_writer(master, rate, seconds, clock, progress)
            done.set()

        flood_start = clock.now()
        writer = threading.Thread(target=write, name="flood-writer")
        writer.start()
        while not done.wait(SAMPLE_S):
            result.rss_max_kb = max(result.rss_max_kb, rss_kb(proc.pid))
            result.pty_backlog_max = max(result.pty_backlog_max, pty_backlog(slave))
            result.in_flight_max = max(result.in_flight_max, progress[0] - listener.flood)
        writer.join()
        result.sent = progress[0]
        end = out["end"]
        result.achieved_rate = result.sent / max(1e-9, end - flood_start)
        times, result.probes_ms = probes_at(
            master, listener, clock, probe_rate, int(after_s * probe_rate), k
        )
        result.probe_offsets_s = [t - end for t in times]
        wait_until = clock.now() + 5
        while listener.flood < result.sent and clock.now() < wait_until:
            time.sleep(0.01)
        result.rss_max_kb = max(result.rss_max_kb, rss_kb(proc.pid))
        result.rss_after_kb = rss_kb(proc.pid)
        result.received = listener.flood
        result.drain_s = listener.last_flood_s - end
        result.seq_missing = listener.missing()
        result.gap_messages = listener.gaps
        result.alive_after = proc.poll() is None
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            result.daemon_exit = proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        if listener is not None:
            listener.stop.set()
            listener.thread.join(5)
            listener.rx.close()
        ctx.term()
        os.close(master)
        os.close(slave)
    result.stderr_tail = err_path.read_text()[-2000:]
    for path in home.glob("sessions/*.ldj"):
        journal = load_journal(path)
        result.journaled += int((journal.onsets["note"] != PROBE_NOTE).sum())
        result.journal_clean = journal.clean
    base = np.array(result.baseline_ms)
    median = float(np.nanmedian(base)) if base.size else float("nan")
    result.threshold_ms = median + max(1.0, median)
    ok = np.flatnonzero(np.array(result.probes_ms) <= result.threshold_ms)  # nan: lost
    if ok.size:
        result.recovery_s = max(0.0, result.probe_offsets_s[int(ok[0])])
    return result


def above(lat: list[float], threshold_ms: float) -> str:
    a = np.array(lat)
    return f"{int((~(a <= threshold_ms)).sum())} of {a.size}"


def _pct(x: list[float]) -> str:
    a = np.array(x)
    a = a[np.isfinite(a)]
    if not a.size:
        return "n/a"
    p50, p99 = np.percentile(a, [50, 99])
    return f"p50 {p50:.3f} ms, p99 {p99:.3f} ms, max {a.max():.3f} ms"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench flood")
    parser.add_argument("--rate", type=float, default=10_000.0, help="flood notes/s")
    parser.add_argument("--seconds", type=float, default=10.0, help="flood duration")
    parser.add_argument("--probe-rate", type=float, default=10.0, help="probe notes/s")
    parser.add_argument("--after", type=float, default=3.0, help="seconds of probes after")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as home:
        r = run_flood(args.rate, args.seconds, Path(home), args.probe_rate, after_s=args.after)
    print(
        f"flood: pty serial → input daemon → loopback TCP, {r.rate:g} notes/s for {r.seconds:g} s"
    )
    print(f"  sent {r.sent} notes at {r.achieved_rate:,.0f} notes/s achieved")
    print(
        f"  received {r.received}, journaled {r.journaled} (clean: {r.journal_clean}), "
        f"sequence gaps {r.seq_missing}, GAP messages {r.gap_messages}"
    )
    print(f"  daemon exit status {r.daemon_exit}")
    print(
        f"  daemon RSS {r.rss_before_kb / 1024:.1f} MB before, max {r.rss_max_kb / 1024:.1f} "
        f"MB during (+{(r.rss_max_kb - r.rss_before_kb) / 1024:.1f} MB), "
        f"{r.rss_after_kb / 1024:.1f} MB after"
    )
    print(f"  max pty backlog {r.pty_backlog_max} bytes, max notes in flight {r.in_flight_max}")
    print(f"  baseline probe latency: {_pct(r.baseline_ms)}")
    print(f"  after the flood: {_pct(r.probes_ms)}")
    first = ", ".join(f"{x:.2f}" for x in r.probes_ms[:5])
    print(f"  first probes after the flood (ms, at +0.0, +{1 / args.probe_rate:g} s, ...): {first}")
    print(f"  drain: last flood onset received {r.drain_s * 1e3:.1f} ms after the flood ended")
    print(
        f"  recovery: first probe back within {r.threshold_ms:.3f} ms (baseline median + "
        f"max(1 ms, median)) sent +{r.recovery_s * 1e3:.0f} ms after the flood's last byte "
        f"(probe period {1e3 / args.probe_rate:.0f} ms)"
    )
    print(
        f"  probes above that threshold: after the flood {above(r.probes_ms, r.threshold_ms)}, "
        f"baseline {above(r.baseline_ms, r.threshold_ms)}"
    )
    return 0
