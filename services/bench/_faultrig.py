"""A supervised live rig driven and watched from outside, for fault tests and recovery figures.

:class:`Rig` runs the real launcher, ``livedrummer up --serial PTY``, on a pseudo-terminal it
owns, so it knows every note the "trigger board" sent: note *i* is the pair
:func:`note_of` ``(i)`` (a mapped note and a velocity >= 64), unique for the first
:data:`CAPACITY` notes, so an onset seen anywhere (on the bus, in the journal) names the note
that was written. It watches the pipeline from outside through the same interfaces a show
technician has:

* the input daemon's stream (a SUB socket on its pub port: every onset it published),
* the synth's pose stream (a SUB socket: show times and the per-piece hit ``glow``, which
  rises only when the synth has received an onset),
* the display's ``frames.jsonl`` (per frame: render time, the pose drawn, the newest pose),
* the launcher's output (the supervisor logs ``NAME ready again S s after it died (pid P)``),
* ``/proc`` for the launcher's children (no psutil).

One thread only: :meth:`Rig.pump` writes notes at a steady rate and drains both sockets
between writes; a reader thread collects the launcher's output lines. Used by
``tests/services/process/test_faults.py`` (assertions) and ``services/bench/recovery.py`` (figures).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.kit.loader import load_kit

from ..process.program import program_argv
from ._paths import WORKDIR

REPO = WORKDIR  # child processes start in the checkout (or the user's folder)
#: Mapped notes of the roland-td map (no hi-hat: its openness needs the pedal stream).
NOTES = (36, 38, 40, 37, 48, 50, 45, 47, 43, 58, 49, 55, 57, 52, 51, 59, 53)
VELOCITIES = 64  # velocities 64..127: every hit glows clearly
CAPACITY = VELOCITIES * len(NOTES)
SERVICES = ("input", "synth", "display")
READY_AGAIN = re.compile(r"(\w+) ready again ([\d.]+) s after it died \(pid (\d+)\)")


def note_of(i: int) -> tuple[int, int]:
    """The (note, velocity) of the ``i``-th note written (unique for i < CAPACITY)."""
    return NOTES[(i // VELOCITIES) % len(NOTES)], 64 + i % VELOCITIES


INDEX = {note_of(i): i for i in range(CAPACITY)}


def children(pid: int) -> dict[str, int]:
    """The launcher's children by service name (the word after ``-m livedrummer``)."""
    out: dict[str, int] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) != pid or len(argv) < 4:
            continue
        name = argv[3].decode(errors="replace")
        if name in SERVICES:
            out[name] = int(entry.name)
    return out


@dataclass
class Recovery:
    name: str
    old_pid: int
    new_pid: int
    killed_at: float  # monotonic
    ready_at: float  # when the launcher's "ready again" line was read
    ready_after_s: float  # as the supervisor measured it (death to ready line)


@dataclass
class Rig:
    """See the module docstring. Use as a context manager; :meth:`start` launches."""

    tmp: Path
    port_base: int
    fps: float = 30.0
    rate_hz: float = 20.0
    extra: Sequence[str] = ()
    written: list[tuple[int, float]] = field(default_factory=list)  # (index, monotonic)
    unsent: list[int] = field(default_factory=list)  # indices the pty refused (buffer full)
    bus: list[tuple[int, float]] = field(default_factory=list)  # (index, onset time_s)
    poses: list[tuple[float, np.ndarray, np.ndarray]] = field(default_factory=list)
    lines: list[tuple[float, str]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.master, slave = os.openpty()
        self.tty = os.ttyname(slave)
        os.close(slave)
        os.set_blocking(self.master, False)
        self.home = self.tmp / "home"
        self.frames_dir = self.tmp / "frames"
        self.ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        kit = load_kit("rock5")
        self.format = p.PoseFormat.from_dtype(pose_dtype(len(kit.pieces)))
        self.proc: subprocess.Popen[str] | None = None
        self._next = 0
        self._next_write = 0.0
        self._lock = threading.Lock()

    # -- life cycle -------------------------------------------------------------------------

    def start(self, timeout_s: float = 60.0) -> None:
        env = {**os.environ, "LIVEDRUMMER_HOME": str(self.home)}
        env.pop("DISPLAY", None)
        env.pop("WAYLAND_DISPLAY", None)
        self.proc = subprocess.Popen(
            [
                *program_argv(),
                "up",
                "--serial",
                self.tty,
                "--port-base",
                str(self.port_base),
                "--frames-dir",
                str(self.frames_dir),
                "--no-png",
                "--fps",
                str(self.fps),
                *self.extra,
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=env,
            cwd=REPO,
        )
        threading.Thread(target=self._read_lines, daemon=True).start()
        self.in_sub = self._sub(self.port_base, p.Kind.ONSET)
        self.pose_sub = self._sub(self.port_base + 10, p.Kind.POSE)
        self.wait_line(lambda s: s.startswith("up: input, synth and display running"), timeout_s)

    def _sub(self, port: int, kind: p.Kind) -> zmq.Socket[bytes]:
        sock = self.ctx.socket(zmq.SUB)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.SUBSCRIBE, p.topic(kind))
        sock.connect(f"tcp://127.0.0.1:{port}")
        return sock

    def _read_lines(self) -> None:
        assert self.proc is not None and self.proc.stdout is not None
        for line in self.proc.stdout:
            with self._lock:
                self.lines.append((time.monotonic(), line.rstrip("\n")))

    def output(self) -> str:
        with self._lock:
            return "\n".join(text for _, text in self.lines)

    def wait_line(self, match: Callable[[str], bool], timeout_s: float) -> str:
        """Pump (writing notes once any are flowing) until the launcher prints a matching line
        (one printed after this call began)."""
        with self._lock:
            seen = len(self.lines)  # only lines printed from now on
        found: list[str] = []

        def check() -> bool:
            nonlocal seen
            with self._lock:
                new = self.lines[seen:]
                seen = len(self.lines)
            found.extend(t for _, t in new if match(t))
            return bool(found)

        self.pump(check, timeout_s, write=bool(self.written))
        if not found:
            raise AssertionError(
                f"launcher never printed the line; output:\n{self.output()[-3000:]}"
            )
        return found[0]

    def stop(self) -> str:
        """SIGTERM the launcher; return its whole output."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        time.sleep(0.1)  # let the reader thread take the last lines (it ends at EOF)
        return self.output()

    def close(self) -> None:
        self.stop()
        for sock in (getattr(self, "in_sub", None), getattr(self, "pose_sub", None)):
            if sock is not None:
                sock.close(0)
        self.ctx.term()
        os.close(self.master)

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- driving and watching ---------------------------------------------------------------

    def pump(self, until: Callable[[], bool], timeout_s: float, write: bool = True) -> bool:
        """Write a note every 1/rate s (if ``write``) and drain both streams until ``until()``."""
        deadline = time.monotonic() + timeout_s
        poller = zmq.Poller()
        poller.register(self.in_sub, zmq.POLLIN)
        poller.register(self.pose_sub, zmq.POLLIN)
        while True:
            if until():
                return True
            now = time.monotonic()
            if now >= deadline:
                return False
            if write and now >= self._next_write:
                self.write_note()
                self._next_write = max(self._next_write + 1.0 / self.rate_hz, now)
            wait = min(deadline, self._next_write if write else deadline) - time.monotonic()
            for sock, _ in poller.poll(max(1, min(50, int(wait * 1000)))):
                self._drain(sock)

    def write_note(self) -> None:
        i = self._next
        if i >= CAPACITY:
            raise AssertionError(f"more than {CAPACITY} notes: identities would repeat")
        note, velocity = note_of(i)
        self._next += 1
        try:
            os.write(self.master, bytes([0x99, note, velocity]))
        except BlockingIOError:
            self.unsent.append(i)
            return
        self.written.append((i, time.monotonic()))

    def _drain(self, sock: zmq.Socket[bytes]) -> None:
        while True:
            try:
                frames = sock.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                return
            if sock is self.in_sub:
                msg = p.decode(frames)
                if msg.kind is p.Kind.ONSET:
                    for row in msg.rows:
                        key = (int(row["note"]), int(row["velocity"]))
                        self.bus.append((INDEX[key], float(row["time_s"])))
            else:
                msg = p.decode(frames, self.format)
                if isinstance(msg.body, p.Pose):
                    rows = msg.body.rows
                    show = msg.body.time_s + rows["time_s"].astype(np.float64)
                    self.poses.append((time.monotonic(), show, rows["glow"].max(axis=1)))

    def settle(self, since: int = 0, timeout_s: float = 10.0) -> bool:
        """Stop writing; wait until every note written so far from index ``since`` is on the bus."""
        want = {i for i, _ in self.written if i >= since}
        return self.pump(lambda: want <= {i for i, _ in self.bus}, timeout_s, write=False)

    # -- faults -----------------------------------------------------------------------------

    def pids(self) -> dict[str, int]:
        assert self.proc is not None
        return children(self.proc.pid)

    def kill(self, name: str, timeout_s: float = 30.0) -> Recovery:
        """SIGKILL one service, keep notes flowing, return once its replacement is ready."""
        old = self.pids()[name]
        killed_at = time.monotonic()
        os.kill(old, signal.SIGKILL)
        line = self.wait_line(lambda s: f"{name} ready again" in s, timeout_s)
        m = READY_AGAIN.search(line)
        assert m is not None and m.group(1) == name, line
        with self._lock:
            ready_at = next(t for t, text in reversed(self.lines) if text == line)
        return Recovery(name, old, int(m.group(3)), killed_at, ready_at, float(m.group(2)))

    # -- what the services left -------------------------------------------------------------

    def frames(self) -> list[dict[str, Any]]:
        """The display's frames.jsonl (the current display process's; a restart rewrites it)."""
        path = self.frames_dir / "frames.jsonl"
        out = []
        for line in path.read_text().splitlines() if path.exists() else []:
            try:
                out.append(json.loads(line))
            except ValueError:  # the line being written
                break
        return out

    def glow_after(self, t: float) -> float:
        """The highest hit glow in pose samples shown at or after shared-clock time ``t``."""
        best = 0.0
        for _, show, glow in self.poses:
            keep = show >= t
            if keep.any():
                best = max(best, float(glow[keep].max()))
        return best

    def newest_pose_s(self) -> float:
        return max((float(show[-1]) for _, show, _ in self.poses), default=0.0)
