"""``livedrummer bench audio``: live sound through a real JACK server, measured at its output.

A private JACK server on the dummy driver (no sound card; ``--period`` frames, default 128;
JACK's default asynchronous mode, real-time scheduling asked for, as a rig runs it; the
``--jack-*`` options change that),
a synth and a ``display --live --headless --no-render --sound`` on it, and this process as the
input daemon: it publishes ``--rate`` onsets a second (a rim click and a woodblock in turn,
short sounds whose attacks stand apart) for ``--seconds`` on the bus, each stamped when it is
sent. A JACK client records everything the display sounds (:mod:`._jackrec`). Printed:

- onset on the bus -> sound at the output, minus D: p50 / p99 / max over every onset, and over
  the onsets where the JACK graph ran steadily (the dummy driver of a loaded machine stalls;
  a stall moves every sound around it);
- onset on the bus -> forwarded by the synth (SHOWN_ONSET, seen here): how many came too late
  to be placed on their sample (later than D less the sound's FIFO);
- the sound process's own counts: onsets placed late (they arrived after their sample was
  written), output underruns, clipped samples;
- JACK's xruns and DSP load (mean and max, sampled every 20 ms): the callback load.

Figures from one run; no assertions. The issue's goal run is ``--seconds 600``; the default
(10 s) is a quick look.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.kit.vocabulary import INSTRUMENTS, ZONES, Zone
from livedrummer.timeline.events import ONSET_DTYPE

from ._jack import JackError, dummy_jack, jack_env
from ._jackrec import JackRecorder, attacks, steady


def onset(t: float, k: int) -> np.ndarray:
    row = np.zeros(1, ONSET_DTYPE)
    row["time_s"], row["channel"], row["velocity"] = t, 9, 100
    row["note"] = 37 if k % 2 == 0 else 76
    row["instrument"] = INSTRUMENTS.index("snare" if k % 2 == 0 else "percussion")
    row["zone"] = ZONES.index(Zone.RIM) if k % 2 == 0 else 0
    return row


def spawn(args: list[str], env: dict[str, str], err: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "services", *args],
        stdout=subprocess.PIPE,
        stderr=err.open("w"),
        text=True,
        env=env,
    )


def stop(proc: subprocess.Popen[str]) -> None:
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(15)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def pct(x: np.ndarray) -> str:
    if not x.size:
        return "n/a"
    q = np.percentile(np.abs(x) * 1000, [50, 90, 99])
    return (
        f"p50 {q[0]:.2f} / p90 {q[1]:.2f} / p99 {q[2]:.2f} / max "
        f"{np.abs(x).max() * 1000:.2f} ms (sizes; signed median "
        f"{np.median(x) * 1000:+.2f})"
    )


def run(
    seconds: float,
    rate: float,
    delay_s: float,
    period: int,
    sync: bool = False,
    realtime: bool = True,
    priority: int | None = None,
) -> int:
    folder = Path(tempfile.mkdtemp(prefix="ldbench-audio-"))
    log = (folder / "jackd.log").open("w")
    with dummy_jack(
        "ldaudio", period=period, log=log, sync=sync, realtime=realtime, priority=priority
    ) as name:
        env = {**os.environ, **jack_env(name)}
        env.pop("DISPLAY", None)
        ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        bus = ctx.socket(zmq.PUB)
        bus.setsockopt(zmq.LINGER, 0)
        port = bus.bind_to_random_port("tcp://127.0.0.1")
        procs: list[subprocess.Popen[str]] = []
        sent: list[float] = []
        came: dict[float, float] = {}  # an onset's bus time -> when the synth forwarded it

        def back(frames: list[bytes]) -> None:
            at = time.monotonic()
            for row in p.decode(frames).rows:
                came.setdefault(round(float(row["time_s"]) - delay_s, 6), at)

        recorder = JackRecorder(env)
        try:
            syn = spawn(
                [
                    "synth",
                    "--sub",
                    f"tcp://127.0.0.1:{port}",
                    "--pub",
                    "tcp://127.0.0.1:*",
                    "--delay-ms",
                    str(delay_s * 1000),
                ],
                env,
                folder / "synth.err",
            )
            procs.append(syn)
            assert syn.stdout is not None
            pub = json.loads(syn.stdout.readline())["pub"]
            disp = spawn(
                [
                    "display",
                    "--live",
                    "--headless",
                    "--no-render",
                    "--sub",
                    pub,
                    "--sound",
                    "--audio-device",
                    "system, JACK",
                    "--fps",
                    "30",
                ],
                env,
                folder / "display.err",
            )
            procs.append(disp)
            assert disp.stdout is not None
            disp.stdout.readline()
            shown = ctx.socket(zmq.SUB)
            shown.setsockopt(zmq.LINGER, 0)
            shown.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.SHOWN_ONSET))
            shown.connect(pub)
            seq, deadline = 0, time.monotonic() + 20
            while not shown.poll(200) and time.monotonic() < deadline:
                bus.send_multipart(
                    p.encode(p.Message(p.Kind.ONSET, onset(time.monotonic(), 0), seq=seq))
                )
                seq += 1
            if not shown.poll(0):
                print("bench audio: no onset came back from the synth", file=sys.stderr)
                return 1
            time.sleep(1.0)
            start = time.monotonic()
            for k in range(round(seconds * rate)):
                due = start + k / rate
                while (left := due - time.monotonic() - 0.002) > 0:  # forwards seen as they come
                    if shown.poll(max(1, int(left * 1000))):
                        back(shown.recv_multipart())
                while time.monotonic() < due:
                    time.sleep(0.0002)
                t = time.monotonic()
                bus.send_multipart(
                    p.encode(p.Message(p.Kind.ONSET, onset(t, k), seq=seq, send_time_s=t))
                )
                seq += 1
                sent.append(t)
                while shown.poll(0):
                    back(shown.recv_multipart())
            until = time.monotonic() + 0.6
            while (left := until - time.monotonic()) > 0:
                if shown.poll(max(1, int(left * 1000))):
                    back(shown.recv_multipart())
        finally:
            for proc in reversed(procs):
                stop(proc)
            rec = recorder.stop()
            ctx.destroy(0)
    err = (folder / "display.err").read_text()
    expected = np.array(sent) + delay_s
    heard = attacks(rec)
    if not heard.size or not expected.size:
        print("bench audio: nothing heard", err[-600:], file=sys.stderr)
        return 1
    near = heard[np.argmin(np.abs(heard[None, :] - expected[:, None]), axis=1)]
    lag = near - expected
    found = np.abs(lag) < 0.1
    ok = steady(rec, expected) & found
    line = next((x for x in err.splitlines() if x.startswith("sound:")), "sound: (no summary)")
    late = re.search(r"(\d+) late", line)
    mode = ("synchronous (-S)" if sync else "asynchronous") + (
        f", real-time (-R{'' if priority is None else f' -P {priority}'})"
        if realtime
        else ", no real-time"
    )
    print(
        f"bench audio: {len(sent)} onsets at {rate:g}/s for {seconds:g} s, D {delay_s * 1000:g}"
        f" ms, JACK dummy {period} frames at 48 kHz ({period / 48:.2f} ms), {mode}; load "
        f"average {os.getloadavg()[0]:.2f}"
    )
    print(f"  heard: {int(found.sum())} of {len(sent)} onsets")
    print(f"  onset on the bus -> sound at the output, - D: {pct(lag[found])}")
    print(f"    where the JACK graph ran steadily ({int(ok.sum())} onsets): {pct(lag[ok])}")
    forward = np.array([came.get(round(t, 6), np.inf) - t for t in sent])
    # the sound process writes about BUFFER_S ahead: an onset forwarded later than D - that
    # cannot be placed on its sample
    in_time = delay_s - 0.0107
    late_fw, unseen = int(np.sum(forward > in_time)), int(np.sum(~np.isfinite(forward)))
    print(
        f"  onset on the bus -> forwarded by the synth (SHOWN_ONSET): "
        f"{pct(forward[np.isfinite(forward)])}; {late_fw} later than D - 10.7 ms (the "
        f"sound's FIFO), {unseen} not seen"
    )
    print(f"  {line}")
    print(
        f"  JACK: {rec.xruns} xruns, DSP load mean {rec.load_mean:.1f} % / max "
        f"{rec.load_max:.1f} %; late onsets {late.group(1) if late else '?'}"
    )
    return 0


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench audio", description=__doc__)
    parser.add_argument("--seconds", type=float, default=10.0, help="how long (default 10)")
    parser.add_argument("--rate", type=float, default=10.0, help="onsets a second (default 10)")
    parser.add_argument("--delay-ms", type=float, default=30.0, help="D (default 30)")
    parser.add_argument("--period", type=int, default=128, help="JACK frames (default 128)")
    parser.add_argument(
        "--jack-sync", action="store_true", help="run jackd synchronous (-S; default: asynchronous)"
    )
    parser.add_argument(
        "--jack-no-realtime",
        action="store_true",
        help="run jackd without real-time scheduling (default: -R)",
    )
    parser.add_argument(
        "--jack-priority",
        type=int,
        metavar="P",
        help="jackd's real-time priority (-P; default: jackd's)",
    )
    args = parser.parse_args(argv)
    try:
        return run(
            args.seconds,
            args.rate,
            args.delay_ms / 1000.0,
            args.period,
            args.jack_sync,
            not args.jack_no_realtime,
            args.jack_priority,
        )
    except JackError as exc:
        print(f"bench audio: {exc}", file=sys.stderr)
        return 2
