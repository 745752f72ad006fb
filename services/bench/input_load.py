"""Input stamps on a loaded machine, against a reference JACK client on the same server.

For each JACK mode (``-S`` synchronous, and JACK's default asynchronous mode) and each load
(no hogs, N = cores and 2 x cores CPU-bound hog processes at normal priority), ``--runs``
runs of ``--seconds`` each: a ``jackd -d dummy`` server, a virtual rtmidi output port as the
kit playing ``--rate`` notes/s at irregular intervals, the real input daemon (``livedrummer
input --midi kit:pads --api jack``) and a reference client written in C
(``services/bench/jack_ref.c``, compiled for the run: needs cc and Debian's libjack-jackd2-dev)
connected to the same kit port. The reference takes, in JACK's process thread, for each
event: ``CLOCK_MONOTONIC`` (the shared clock) and the event's frame time converted by JACK
(``jack_frames_to_time``; on the wire but not compared: the dummy driver's frame
clock wanders by milliseconds against the system clock); it never waits for anything.

Per note: *stamp error* = the daemon's stamp minus the reference's CLOCK_MONOTONIC stamp
(both clients see the note in the same cycle; the daemon's stamp comes from rtmidi's own
delta times, see :mod:`services.input.midiport`). *Lost* = notes the reference received that
the daemon did not publish; *off server* = notes the kit sent that the reference never saw
(lost before any client: the sender or the server). ``--code DIR`` runs the daemon
from another checkout of the repository (an older commit), so two designs are compared in
one run under the same load. ``--stalls`` stops the daemon's process for 1-20 ms every 5-30
ms while the kit plays (its JACK thread then misses cycles, as on a virtual machine whose core
is taken away, realtime priority or not): in the asynchronous mode the server does not wait
for it and the MIDI of a cycle it missed is lost; with ``-S`` it waits. Prints p50/p99/max in
ms over all runs of a row; no assertions.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.timeline.clock import MonotonicClock

from ..process.program import PACKAGE
from ._hogs import hog_levels, hogs
from ._jack import JackError, dummy_jack, jack_env
from ._paths import HERE, WORKDIR
from .input_latency import _fmt, key

#: JACK modes by name: (synchronous -S, realtime -R).
MODES = {
    "sync": (True, True),
    "async": (False, True),
    "sync-nort": (True, False),
    "async-nort": (False, False),
}


def modes_list(spec: str) -> list[str]:
    """``--modes``: names of :data:`MODES`, comma-separated (an argparse ``type``)."""
    modes = spec.split(",")
    if bad := [m for m in modes if m not in MODES]:
        raise argparse.ArgumentTypeError(f"{bad[0]!r}: expected modes of {', '.join(MODES)}")
    return modes


def package_in(code: Path | None) -> str:
    """The package ``-m`` runs in ``code`` (a checkout, old or new), or this one for None."""
    if code is None:
        return PACKAGE
    return "services" if (code / "services" / "__main__.py").is_file() else "livedrummer"


def build_reference(folder: Path) -> Path:
    """Compile services/bench/jack_ref.c into ``folder``; JackError naming what is missing."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise JackError("no C compiler (Debian: apt-get install gcc)")
    exe = folder / "jack_ref"
    done = subprocess.run(
        [cc, "-O2", "-o", str(exe), str(HERE / "jack_ref.c"), "-ljack"],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1:]
        raise JackError(f"cannot build the reference client (Debian: libjack-jackd2-dev): {last}")
    return exe


class Reference:
    """The C reference client: lines 'frame_us mono_ns status d1 d2' on its stdout."""

    def __init__(self, exe: Path, source: str, env: dict[str, str]) -> None:
        self.proc = subprocess.Popen(
            [str(exe), source],
            stdout=subprocess.PIPE,
            text=True,
            env=env,
            stderr=subprocess.DEVNULL,
        )
        assert self.proc.stdout is not None
        first = self.proc.stdout.readline().split()
        if not first or first[0] != "ready":
            raise JackError("the reference client did not start")
        self.events: list[tuple[float, tuple[int, int]]] = []
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            f = line.split()
            if len(f) == 5 and int(f[2]) & 0xF0 == 0x90:
                self.events.append((int(f[1]) * 1e-9, (int(f[3]), int(f[4]))))

    def close(self) -> None:
        self.proc.terminate()
        self.proc.wait(10)
        self._thread.join(5)


def stall(proc: subprocess.Popen[str], while_alive: threading.Thread, seed: int) -> None:
    """Stop ``proc`` for 1-20 ms every 5-30 ms while ``while_alive`` runs: what a virtual
    machine that takes its core away does to the daemon's JACK thread, realtime or not."""
    rng = np.random.default_rng(1000 + seed)
    while while_alive.is_alive() and proc.poll() is None:
        proc.send_signal(signal.SIGSTOP)
        time.sleep(float(rng.uniform(0.001, 0.020)))
        proc.send_signal(signal.SIGCONT)
        time.sleep(float(rng.uniform(0.005, 0.030)))


def one_run(
    mode: str,
    n_hogs: int,
    seconds: float,
    rate: float,
    code: Path | None,
    exe: Path,
    seed: int,
    stalls: bool = False,
) -> dict[str, Any]:
    import rtmidi

    clock = MonotonicClock()
    rng = np.random.default_rng(seed)
    gaps = rng.uniform(0.3, 1.7, int(seconds * rate)) / rate  # a drummer, not a metronome
    sync, realtime = MODES[mode]
    with (
        tempfile.TemporaryDirectory() as home,
        dummy_jack("ldload", period=128, sync=sync, realtime=realtime) as server,
    ):
        env = {**os.environ, **jack_env(server), "LIVEDRUMMER_HOME": home}
        if code is not None:
            env["PYTHONPATH"] = str(code)
        os.environ.update(jack_env(server))
        kit = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
        kit.open_virtual_port("pads")
        ref = Reference(exe, "kit:pads", env)
        daemon = subprocess.Popen(
            [
                sys.executable,
                "-m",
                package_in(code),
                "input",
                "--midi",
                "kit:pads",
                "--api",
                "jack",
                "--map",
                "roland-td",
                "--pub",
                "tcp://127.0.0.1:*",
                "--control",
                "tcp://127.0.0.1:*",
                "--wait-subscribers",
                "1",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            env=env,
            cwd=code or WORKDIR,
        )
        ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
        got: dict[tuple[int, int], float] = {}
        sent: list[tuple[int, int]] = []
        try:
            assert daemon.stdout is not None
            sub.connect(json.loads(daemon.stdout.readline())["pub"])
            deadline = clock.now() + 10
            while clock.now() < deadline:  # until the subscription and the port are through
                kit.send_message([0x99, 36, 1])
                if sub.poll(100):
                    break
            while sub.poll(300):
                sub.recv_multipart()
            ref.events.clear()

            def play() -> None:
                t = clock.now()
                cancel = threading.Event()
                for i, gap in enumerate(gaps):
                    t += float(gap)
                    clock.wait_until(t, cancel)
                    k = key(i)
                    kit.send_message([0x99, *k])
                    sent.append(k)

            with hogs(n_hogs):
                time.sleep(0.5)  # let the hogs spin up
                player = threading.Thread(target=play)
                player.start()
                if stalls:
                    threading.Thread(target=stall, args=(daemon, player, seed), daemon=True).start()
                end = clock.now() + float(gaps.sum()) + 3.0
                while clock.now() < end and (player.is_alive() or len(got) < len(sent)):
                    if sub.poll(100):
                        msg = p.decode(sub.recv_multipart())
                        for t, note, vel in msg.rows[["time_s", "note", "velocity"]].tolist():
                            got[(int(note), int(vel))] = float(t)
                player.join()
        finally:
            daemon.terminate()
            daemon.wait(10)
            sub.close(0)
            ctx.term()
            ref.close()
            kit.close_port()
            kit.delete()
    seen = {k: mono for mono, k in ref.events}
    both = [k for k in sent if k in got and k in seen]
    return {
        "sent": len(sent),
        "lost": sum(k in seen and k not in got for k in sent),
        "off_server": sum(k not in seen for k in sent),
        "err": np.array([got[k] - seen[k] for k in both]) * 1e3,
    }


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench input_load")
    parser.add_argument("--runs", type=int, default=10, help="runs per row (default 10)")
    parser.add_argument("--seconds", type=float, default=20.0, help="seconds a run (default 20)")
    parser.add_argument("--rate", type=float, default=20.0, help="notes/s, mean (default 20)")
    parser.add_argument(
        "--modes",
        type=modes_list,
        default="sync,async",
        help=f"JACK modes, of {', '.join(MODES)} (default sync,async)",
    )
    parser.add_argument(
        "--hogs",
        type=hog_levels,
        default="0,1x,2x",
        help="hogs per row: a count or Nx cores (default 0,1x,2x)",
    )
    parser.add_argument(
        "--stalls",
        action="store_true",
        help="stop the daemon for 1-20 ms every 5-30 ms while the kit plays "
        "(a virtual machine taking its core away)",
    )
    parser.add_argument(
        "--code",
        type=Path,
        default=None,
        help="checkout whose input daemon runs (default this one)",
    )
    args = parser.parse_args(argv)
    cores = os.cpu_count() or 1
    levels: list[int] = args.hogs
    try:
        with tempfile.TemporaryDirectory() as tmp:
            exe = build_reference(Path(tmp))
            print(
                f"input stamps vs a C reference client on the same JACK server; "
                f"{args.runs} x {args.seconds:g} s at ~{args.rate:g} notes/s; {cores} cores; "
                f"daemon from {args.code or 'this code'}"
                f"{'; the daemon stalled 1-20 ms every 5-30 ms' if args.stalls else ''}"
            )
            print(
                "ms, p50 / p99 / max; JACK modes: sync = -S -R, async = JACK's default "
                "(-R, no -S); -nort: --no-realtime"
            )
            print(
                f"{'mode':>10} {'hogs':>4} {'sent':>6} {'lost':>5} {'off server':>10}  "
                f"{'stamp - reference':>22}"
            )
            for mode in args.modes:
                for n_hogs in levels:
                    rows = [
                        one_run(
                            mode, n_hogs, args.seconds, args.rate, args.code, exe, seed, args.stalls
                        )
                        for seed in range(args.runs)
                    ]
                    err = np.concatenate([r["err"] for r in rows])
                    print(
                        f"{mode:>10} {n_hogs:>4} {sum(r['sent'] for r in rows):>6} "
                        f"{sum(r['lost'] for r in rows):>5} "
                        f"{sum(r['off_server'] for r in rows):>10}  {_fmt(err)}",
                        flush=True,
                    )
    except JackError as exc:
        print(f"bench input_load: {exc}", file=sys.stderr)
        return 2
    return 0
