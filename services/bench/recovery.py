"""Recovery benchmark: how long each fault keeps the live pipeline from working.

Figures (medians of ``--kills`` / ``--replugs`` runs; no assertions):

* **kill to working again per process** after ``kill -9``, in a real ``livedrummer up
  --serial PTY`` session fed notes at 20/s (:class:`bench._faultrig.Rig`), at rest and with
  ``--hogs`` CPU-bound processes running: from the kill to the input daemon's first note on
  the bus, to the new display's first frame drawn with a pose, to the first frame drawing a
  pose of the new synth. Beside it the supervisor's own figure, from the death (its pidfd)
  to the new process's ready line (``NAME ready again S s after it died``; a service is
  ready when it does its job), which includes the restart back-off, printed too (0.1 s for
  a crash after a healthy run, doubling while a service keeps dying within 10 s of its
  start, as it does from one round to the next here), and the start-up alone.
* **display stale-pose time** when the synth is killed: from the last frame drawn with a
  pose newer than the previous frame's to the first frame drawing a pose from the restarted
  synth (render times in the display's ``frames.jsonl``).
* **serial replug**: an input daemon on a pty behind a symlink; the pty is closed (unplug)
  and a new one linked at the same path (replug); the figure is replug → first note on the
  bus, with notes written every 5 ms from the replug on.
* **JACK replug**: the same with a virtual rtmidi JACK output port closed and created again
  under the same name (a ``jackd -d dummy -S`` server is started for the run; skipped when
  jackd is not installed).

``livedrummer bench recovery [--kills N] [--replugs N] [--hogs 0,1x]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

import zmq

from livedrummer import protocol as p
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.clock import MonotonicClock

from ..input.base import Source
from ..input.daemon import DaemonConfig, InputDaemon
from ._hogs import hog_levels, hogs
from ._ports import free_port_base

PROBE_EVERY_S = 0.005
#: Pose messages a killed synth had sent arrive within this; a restart takes far longer.
IN_FLIGHT_S = 0.05


@contextmanager
def _daemon(source: Source, clock: MonotonicClock, tmp: Path) -> Iterator[zmq.Socket[bytes]]:
    """An input daemon on ``source`` with the default reconnect interval; yields a SUB."""
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    config = DaemonConfig(
        pub="tcp://127.0.0.1:*",
        control="tcp://127.0.0.1:*",
        sessions_dir=tmp / "sessions",
        wait_subscribers=1,
    )
    daemon = InputDaemon(source, config, clock, ctx)
    daemon.start()
    stop = threading.Event()
    thread = threading.Thread(target=daemon.run, args=(stop,), daemon=True)
    thread.start()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
    sub.connect(daemon.endpoints["pub"])
    try:
        yield sub
    finally:
        stop.set()
        thread.join(5)
        sub.close(0)
        ctx.term()


def _first_note(sub: zmq.Socket[bytes], send: Callable[[], object], timeout_s: float) -> float:
    """Send a note every PROBE_EVERY_S until one is on the bus; seconds it took (inf: none)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        send()
        if sub.poll(int(PROBE_EVERY_S * 1000)):
            msg = p.decode(sub.recv_multipart())
            if msg.kind is p.Kind.ONSET:
                took = time.monotonic() - t0
                while sub.poll(100):  # the probes still in flight
                    sub.recv_multipart()
                return took
    return float("inf")


def serial_replug(tmp: Path, replugs: int = 1) -> float:
    """Median seconds from replugging a pty (same path) to its first note on the bus."""
    from ..input.serialport import SerialSource

    link = tmp / "ttyDRUM"
    master, slave = os.openpty()
    link.symlink_to(os.ttyname(slave))
    os.close(slave)
    clock = MonotonicClock()
    source = SerialSource(str(link), clock, MessageDecoder(load_note_map("roland-td")))
    figures = []
    with _daemon(source, clock, tmp) as sub:
        try:
            if _first_note(sub, lambda: os.write(master, b"\x99\x26\x64"), 10) == float("inf"):
                raise RuntimeError("serial replug: the daemon never published a note")
            for _ in range(replugs):
                os.close(master)  # unplug
                link.unlink()
                master = -1
                deadline = time.monotonic() + 5
                while source.is_open and time.monotonic() < deadline:
                    time.sleep(0.01)  # watching another thread's state, not a handshake
                master, slave = os.openpty()  # replug, maybe under another /dev/pts number
                link.symlink_to(os.ttyname(slave))
                os.close(slave)
                figures.append(_first_note(sub, partial(os.write, master, b"\x99\x26\x64"), 10))
        finally:
            if master >= 0:
                os.close(master)
    return statistics.median(figures)


def jack_replug(tmp: Path, replugs: int = 1) -> float:
    """Median seconds from re-creating a JACK port (same name) to its first note on the bus.

    Needs a running JACK server (``JACK_DEFAULT_SERVER`` names it).
    """
    import rtmidi

    from ..input.midiport import MidiPortSource

    def plug() -> Any:
        out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
        out.open_virtual_port("pads")
        return out

    clock = MonotonicClock()
    kit = plug()
    source = MidiPortSource(
        "kit:pads", clock, MessageDecoder(load_note_map("roland-td")), api="jack"
    )
    figures = []
    with _daemon(source, clock, tmp) as sub:
        try:
            if _first_note(sub, lambda: kit.send_message([0x99, 38, 100]), 10) == float("inf"):
                raise RuntimeError("JACK replug: the daemon never published a note")
            for _ in range(replugs):
                kit.close_port()  # unplug
                kit.delete()
                deadline = time.monotonic() + 5
                while source.is_open and time.monotonic() < deadline:
                    time.sleep(0.01)  # watching another thread's state, not a handshake
                kit = plug()
                figures.append(_first_note(sub, partial(kit.send_message, [0x99, 38, 100]), 10))
        finally:
            kit.delete()
    return statistics.median(figures)


@contextmanager
def _jackd() -> Iterator[str | None]:
    """A ``jackd -d dummy -S`` server for the run (None when jackd is missing or fails)."""
    from ._jack import JackError, dummy_jack, jack_env

    old = {k: os.environ.get(k) for k in jack_env("")}
    try:
        with dummy_jack("ldbench") as name:
            os.environ.update(jack_env(name))
            yield name
    except JackError:
        yield None
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def kills(
    tmp: Path, rounds: int, n_hogs: int = 0
) -> tuple[dict[str, list[float]], dict[str, list[float]], dict[str, list[float]], list[float]]:
    """Kill input, synth, display in turn, ``rounds`` times, with ``n_hogs`` CPU-bound processes
    running: per service the time from the kill to the pipeline working again (see
    :func:`_working_again`), the supervisor's own death-to-ready figure and its back-off;
    and the display's stale-pose time per synth kill."""

    from ._faultrig import Rig

    back: dict[str, list[float]] = {"input": [], "synth": [], "display": []}
    ready: dict[str, list[float]] = {"input": [], "synth": [], "display": []}
    backoff: dict[str, list[float]] = {"input": [], "synth": [], "display": []}
    stale: list[float] = []
    with Rig(tmp, free_port_base()) as rig:
        rig.start()
        rig.pump(lambda: len(rig.bus) >= 20, 20)
        with hogs(n_hogs):
            for _ in range(rounds):
                for name in ("input", "synth", "display"):
                    rec = rig.kill(name)
                    ready[name].append(rec.ready_after_s)
                    line = next(t for _, t in reversed(rig.lines) if f"{name} exited with" in t)
                    backoff[name].append(float(line.rsplit(" in ", 1)[1].split()[0]))
                    rig.pump(lambda: False, 2.0)
                    back[name].append(_working_again(rig, name, rec.killed_at))
                    if name == "synth":
                        stale.append(_stale_s(rig.frames(), rec.killed_at))
        rig.stop()
    return back, ready, backoff, stale


def _working_again(rig: Any, name: str, killed_at: float) -> float:
    """Seconds from the kill to the replacement doing its job: the input daemon's first note
    on the bus (its stamp), the display's first frame drawn with a pose (done), the first
    frame drawn after the new synth's first pose message reached the rig."""
    if name == "input":
        return min((t for _, t in rig.bus if t > killed_at), default=float("inf")) - killed_at
    frames = [f for f in rig.frames() if f["render_s"] > killed_at]
    if name == "display":
        done = (f["done_s"] for f in frames if f["pose_s"] is not None)
    else:  # the first pose message after the old synth's last ones in flight, then drawn
        first = min((t for t, _, _ in rig.poses if t > killed_at + IN_FLIGHT_S), default=None)
        done = (f["done_s"] for f in frames if first is not None and f["render_s"] >= first)
    return next(done, float("inf")) - killed_at


def _stale_s(frames: list[dict[str, Any]], killed_at: float) -> float:
    """How long the display drew one held pose around ``killed_at``: from the first frame
    whose newest pose is the held one to the first frame with a newer pose."""
    window = [(f["render_s"], f["newest_s"]) for f in frames if f["render_s"] > killed_at - 1.0]
    runs = []
    i = 0
    while i < len(window):
        j = i
        while j + 1 < len(window) and window[j + 1][1] == window[i][1]:
            j += 1
        if j + 1 < len(window) and window[i][1] is not None:
            runs.append(window[j + 1][0] - window[i][0])
        i = j + 1
    return max(runs, default=float("nan"))


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench recovery", description=__doc__)
    parser.add_argument("--kills", type=int, default=3, help="kill rounds (default 3)")
    parser.add_argument("--replugs", type=int, default=5, help="replugs per device (default 5)")
    parser.add_argument(
        "--hogs",
        type=hog_levels,
        default="0,1x",
        help="kill rounds at rest and loaded: hog processes, a count or Nx cores (default 0,1x)",
    )
    args = parser.parse_args(argv)
    levels: list[int] = args.hogs
    with tempfile.TemporaryDirectory() as tmp_text:
        tmp = Path(tmp_text)
        for n_hogs in levels:
            back, ready, backoff, stale = kills(tmp / f"up{n_hogs}", args.kills, n_hogs)
            print(f"kill -9 with {n_hogs} CPU hogs (median of {args.kills}; back-off included; s):")
            print(
                f"  {'':<8} {'kill -> working':>16} {'supervisor: death -> ready':>27}"
                f" {'start-up':>9}"
            )
            for name, values in back.items():
                startup = statistics.median(
                    v - b for v, b in zip(ready[name], backoff[name], strict=True)
                )
                print(
                    f"  {name:<8} {statistics.median(values):>16.2f} "
                    f"{statistics.median(ready[name]):>27.2f} {startup:>9.2f}  (all: "
                    f"{', '.join(f'{v:.2f}' for v in values)}; back-off "
                    f"{', '.join(f'{v:.1f}' for v in backoff[name])})"
                )
            each = ", ".join(f"{v:.2f}" for v in stale)
            print(
                f"  display stale-pose time while the synth restarts: median "
                f"{statistics.median(stale):.2f} s (all: {each})"
            )
        (tmp / "serial").mkdir()
        serial = serial_replug(tmp / "serial", args.replugs)
        with _jackd() as server:
            jack = None
            if server is not None:
                (tmp / "jack").mkdir()
                jack = jack_replug(tmp / "jack", args.replugs)
    print(
        f"serial replug -> first note on the bus: median {serial * 1000:.0f} ms of {args.replugs}"
    )
    if jack is None:
        print("JACK replug: not measured (jackd not installed or did not start)")
    else:
        print(
            f"JACK replug -> first note on the bus: median {jack * 1000:.0f} ms of {args.replugs}"
        )
    return 0
