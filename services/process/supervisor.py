"""The launcher's process supervisor: start in order with a ready handshake, restart, stop.

``livedrummer up`` runs several services (input daemon, synthesizer, display), each its own
process so each can crash, restart and move machine alone. The supervisor:

* starts them in the given order and waits for each to report ready
  (:mod:`services.process.notify`: one line on a pipe) before starting the next — no sleeps; a
  service that exits or stays silent past its ``ready_timeout_s`` fails the start-up with its name;
* restarts a service that dies, with exponential back-off (reset after it has run for a while)
  so a service that crashes at once does not spin; every restart is logged and counted, and
  when the new process reports ready the time since the old one died is logged and kept in
  :attr:`Supervisor.recoveries` (the figure ``livedrummer bench recovery`` reports);
* stops everything on :meth:`Supervisor.stop` (the CLI calls it on Ctrl-C / SIGTERM): SIGTERM
  in reverse start order, then SIGKILL for any process still alive after ``stop_timeout_s``.

It is single-threaded: a child's death and a ready line are both events on file descriptors
multiplexed with :mod:`selectors`: the notify pipes, and per child a pidfd (Linux >= 5.3),
readable the moment the child dies, so a death is learnt of at once, never by a poll. The
death is timed when its pidfd wakes the supervisor; where pidfds are missing, a self-pipe
woken by SIGCHLD does the same job. A service's "ready" is its own word that it does its job
(the synth after its first poses are published, the display after its first frame with a
pose is drawn), so a recovery figure is from the death to the service working again.

Limits: under CPU load the supervisor itself may run late, so the time it logs can start
after the real death; ``livedrummer bench recovery`` times from the kill instead.
"""

from __future__ import annotations

import logging
import os
import selectors
import signal
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from livedrummer.errors import LivedrummerError

from .notify import NOTIFY_FD_ENV

log = logging.getLogger(__name__)


#: Selector data of a child's pidfd: (EXITED, service name).
EXITED = "exited"


def _pidfd(pid: int) -> int | None:
    """A pidfd for ``pid`` (readable once it exits), or None where the OS has none."""
    try:
        return os.pidfd_open(pid)
    except (AttributeError, OSError):
        return None


class SupervisorError(LivedrummerError):
    """A service could not be started."""


@dataclass(frozen=True)
class ServiceSpec:
    """How to run one service."""

    name: str
    argv: Sequence[str]
    env: dict[str, str] = field(default_factory=dict)
    ready_timeout_s: float = 30.0
    restart: bool = True
    ends_rig: bool = False  # exit status 0 means the user is done (a window closed): no restart
    stdout_to_stderr: bool = False  # keep the launcher's stdout its own (JSON lines)


@dataclass
class _Running:
    spec: ServiceSpec
    proc: subprocess.Popen[bytes]
    notify_fd: int | None
    started_at: float
    pidfd: int | None = None
    exited_at: float | None = None  # when its pidfd said it died
    ready: bool = False
    detail: str = ""
    buffer: bytes = b""
    died_at: float | None = None  # when the process this one replaces exited


@dataclass
class Backoff:
    """Restart delay: doubles on each quick crash, resets after a healthy run."""

    first_s: float = 0.1
    max_s: float = 5.0
    healthy_after_s: float = 10.0
    current_s: float = 0.0

    def next_delay(self, ran_for_s: float) -> float:
        if ran_for_s >= self.healthy_after_s or self.current_s == 0.0:
            self.current_s = self.first_s
        else:
            self.current_s = min(self.max_s, self.current_s * 2)
        return self.current_s


class Supervisor:
    """Runs services (see the module docstring). Not thread-safe; one per launcher."""

    def __init__(self, specs: Sequence[ServiceSpec], stop_timeout_s: float = 5.0) -> None:
        self.specs = list(specs)
        self.stop_timeout_s = stop_timeout_s
        self.restarts: dict[str, int] = {s.name: 0 for s in specs}
        #: Per service: seconds from a process's death to its replacement's ready line.
        self.recoveries: dict[str, list[float]] = {s.name: [] for s in specs}
        self._running: dict[str, _Running] = {}
        self._backoff: dict[str, Backoff] = {s.name: Backoff() for s in specs}
        self._pending: dict[str, float] = {}  # name -> monotonic time to restart at
        self._died_at: dict[str, float] = {}  # name -> when its last process exited
        self.finished: set[str] = set()  # ``ends_rig`` services that exited with status 0
        self._selector = selectors.DefaultSelector()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_w, False)
        os.set_blocking(self._wake_r, False)
        self._selector.register(self._wake_r, selectors.EVENT_READ, None)
        self._stopping = False
        self._signals: tuple[int, object] | None = None  # previous wakeup fd and SIGCHLD handler

    # -- life cycle -------------------------------------------------------------------------

    def start(self) -> None:
        """Start every service in order, each after the previous one is ready."""
        old_fd = signal.set_wakeup_fd(self._wake_w)
        # A handler (even one doing nothing) makes SIGCHLD write to the wakeup fd.
        self._signals = (old_fd, signal.signal(signal.SIGCHLD, lambda *_: None))
        for spec in self.specs:
            self._spawn(spec)
            deadline = time.monotonic() + spec.ready_timeout_s
            while not self._running[spec.name].ready:
                if self._running[spec.name].proc.poll() is not None:
                    code = self._running[spec.name].proc.returncode
                    self.stop()
                    raise SupervisorError(f"service {spec.name!r} exited with {code} before ready")
                left = deadline - time.monotonic()
                if left <= 0:
                    self.stop()
                    raise SupervisorError(
                        f"service {spec.name!r} not ready after {spec.ready_timeout_s:g} s"
                    )
                self._poll(min(left, 0.5))
            log.info("%s ready %s", spec.name, self._running[spec.name].detail)

    def quit_by_user(self, name: str) -> bool:
        """True once ``name`` (an ``ends_rig`` service) exited with status 0."""
        return name in self.finished

    def run_once(self, timeout_s: float = 0.5) -> None:
        """Handle events for up to ``timeout_s``: ready lines, deaths, due restarts.

        Returns early for a due restart, so a back-off of 0.1 s is 0.1 s, not ``timeout_s``.
        """
        if self._pending:
            due = min(self._pending.values()) - time.monotonic()
            timeout_s = max(0.0, min(timeout_s, due))
        self._poll(timeout_s)
        self._reap()
        now = time.monotonic()
        for name, due in list(self._pending.items()):
            if now >= due and not self._stopping:
                del self._pending[name]
                self._spawn(self._spec(name), self._died_at.pop(name, None))

    def serve_forever(self) -> None:
        while not self._stopping:
            self.run_once()

    def stop(self) -> None:
        """Stop all services: SIGTERM in reverse order, then SIGKILL after the timeout."""
        self._stopping = True
        self._pending.clear()
        running = list(self._running.values())
        for r in reversed(running):
            if r.proc.poll() is None:
                r.proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + self.stop_timeout_s
        for r in reversed(running):
            try:
                r.proc.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                log.warning("%s did not stop on SIGTERM; killing it", r.spec.name)
                r.proc.kill()
                r.proc.wait()
            self._close_notify(r)
            self._close_pidfd(r)
        self._running.clear()
        if self._signals is not None:
            old_fd, old_handler = self._signals
            signal.set_wakeup_fd(old_fd)
            signal.signal(signal.SIGCHLD, old_handler)  # type: ignore[arg-type]
            self._signals = None

    def request_stop(self) -> None:
        """Ask :meth:`serve_forever` to return (safe from a signal handler)."""
        self._stopping = True
        try:
            os.write(self._wake_w, b"x")
        except BlockingIOError:
            pass

    def pid(self, name: str) -> int | None:
        r = self._running.get(name)
        return None if r is None or r.proc.poll() is not None else r.proc.pid

    def is_ready(self, name: str) -> bool:
        r = self._running.get(name)
        return r is not None and r.ready and r.proc.poll() is None

    # -- internals --------------------------------------------------------------------------

    def _spec(self, name: str) -> ServiceSpec:
        return next(s for s in self.specs if s.name == name)

    def _spawn(self, spec: ServiceSpec, died_at: float | None = None) -> None:
        read_fd, write_fd = os.pipe()
        env = {**os.environ, **spec.env, NOTIFY_FD_ENV: str(write_fd)}
        out = sys.stderr.fileno() if spec.stdout_to_stderr else None
        proc = subprocess.Popen(list(spec.argv), env=env, pass_fds=(write_fd,), stdout=out)
        os.close(write_fd)
        os.set_blocking(read_fd, False)
        self._selector.register(read_fd, selectors.EVENT_READ, spec.name)
        pidfd = _pidfd(proc.pid)
        if pidfd is not None:
            self._selector.register(pidfd, selectors.EVENT_READ, (EXITED, spec.name))
        self._running[spec.name] = _Running(
            spec, proc, read_fd, time.monotonic(), pidfd=pidfd, died_at=died_at
        )
        log.info("started %s (pid %d)", spec.name, proc.pid)

    def _poll(self, timeout_s: float) -> None:
        for key, _ in self._selector.select(timeout_s):
            if key.data is None:
                try:
                    while os.read(self._wake_r, 512):
                        pass
                except BlockingIOError:
                    pass
                continue
            if isinstance(key.data, tuple):  # a pidfd: that child has died, now
                r = self._running.get(key.data[1])
                if r is not None and r.pidfd == key.fd:
                    r.exited_at = time.monotonic()
                    self._close_pidfd(r)
                continue
            r = self._running.get(key.data)
            if r is not None and r.notify_fd == key.fd:
                self._read_notify(r)

    def _read_notify(self, r: _Running) -> None:
        if r.notify_fd is None:
            return
        try:
            chunk = os.read(r.notify_fd, 4096)
        except BlockingIOError:
            return
        if not chunk:  # writer closed (after READY, or the process died)
            self._close_notify(r)
            return
        r.buffer += chunk
        while b"\n" in r.buffer:
            line, r.buffer = r.buffer.split(b"\n", 1)
            text = line.decode(errors="replace")
            if text.startswith("READY") and not r.ready:
                r.ready = True
                r.detail = text[5:].strip()
                if r.died_at is not None:
                    took = time.monotonic() - r.died_at
                    self.recoveries[r.spec.name].append(took)
                    log.warning(
                        "%s ready again %.3f s after it died (pid %d)",
                        r.spec.name,
                        took,
                        r.proc.pid,
                    )

    def _close_notify(self, r: _Running) -> None:
        if r.notify_fd is not None:
            self._selector.unregister(r.notify_fd)
            os.close(r.notify_fd)
            r.notify_fd = None

    def _close_pidfd(self, r: _Running) -> None:
        if r.pidfd is not None:
            self._selector.unregister(r.pidfd)
            os.close(r.pidfd)
            r.pidfd = None

    def _reap(self) -> None:
        for name, r in list(self._running.items()):
            code = r.proc.poll()
            if code is None or self._stopping:
                continue
            self._close_notify(r)
            self._close_pidfd(r)
            del self._running[name]
            if code == 0 and r.spec.ends_rig:
                log.info("%s finished", name)
                self.finished.add(name)
                continue
            if not r.spec.restart:
                log.warning("%s exited with %s; not restarting", name, code)
                continue
            died = r.exited_at if r.exited_at is not None else time.monotonic()
            delay = self._backoff[name].next_delay(died - r.started_at)
            self.restarts[name] += 1
            self._died_at[name] = died
            log.warning(
                "%s exited with %s; restart #%d in %.1f s", name, code, self.restarts[name], delay
            )
            self._pending[name] = died + delay
