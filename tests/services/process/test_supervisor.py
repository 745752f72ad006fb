"""The launcher's supervisor with real child processes: order, readiness, restarts, stop."""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from services.process.supervisor import Backoff, ServiceSpec, Supervisor, SupervisorError

REPO = Path(__file__).resolve().parents[3]


def child(code: str, name: str, **kw: object) -> ServiceSpec:
    prelude = "import sys, time, signal\nfrom services.process.notify import ready\n"
    return ServiceSpec(
        name, [sys.executable, "-c", prelude + code], env={"PYTHONPATH": str(REPO)}, **kw
    )  # type: ignore[arg-type]


def serving(log: Path, name: str) -> ServiceSpec:
    code = (
        f"open({str(log)!r}, 'a').write('start {name}\\n')\n"
        "time.sleep(0.3)\n"
        f"open({str(log)!r}, 'a').write('ready {name}\\n')\n"
        f"ready('{name} up')\n"
        "time.sleep(120)\n"
    )
    return child(code, name)


def wait_for(predicate: Callable[[], bool], sup: Supervisor, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached"
        sup.run_once(0.1)


def test_services_start_in_order_after_each_is_ready(tmp_path: Path) -> None:
    log = tmp_path / "log"
    sup = Supervisor([serving(log, "a"), serving(log, "b")])
    try:
        sup.start()
        assert log.read_text().split("\n")[:4] == ["start a", "ready a", "start b", "ready b"]
        assert sup.is_ready("a") and sup.is_ready("b")
    finally:
        sup.stop()
    assert sup.pid("a") is None and sup.pid("b") is None


def test_a_killed_service_is_restarted_and_the_other_keeps_running(tmp_path: Path) -> None:
    log = tmp_path / "log"
    sup = Supervisor([serving(log, "a"), serving(log, "b")])
    try:
        sup.start()
        pid_a, pid_b = sup.pid("a"), sup.pid("b")
        assert pid_a is not None
        os.kill(pid_a, signal.SIGKILL)
        wait_for(lambda: sup.is_ready("a") and sup.pid("a") != pid_a, sup)
        assert sup.restarts == {"a": 1, "b": 0}
        assert sup.pid("b") == pid_b
    finally:
        sup.stop()


def test_exit_before_ready_names_the_service() -> None:
    sup = Supervisor([child("sys.exit(3)", "synth")])
    with pytest.raises(SupervisorError, match="service 'synth' exited with 3 before ready"):
        sup.start()


def test_silent_service_times_out() -> None:
    sup = Supervisor([child("time.sleep(60)", "display", ready_timeout_s=0.5)])
    with pytest.raises(SupervisorError, match=r"service 'display' not ready after 0\.5 s"):
        sup.start()


def test_stop_kills_a_service_that_ignores_sigterm() -> None:
    code = "signal.signal(signal.SIGTERM, signal.SIG_IGN)\nready()\ntime.sleep(60)\n"
    sup = Supervisor([child(code, "stubborn")], stop_timeout_s=0.5)
    sup.start()
    pid = sup.pid("stubborn")
    t0 = time.monotonic()
    sup.stop()
    assert time.monotonic() - t0 < 5
    assert pid is not None
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


def test_backoff_doubles_on_quick_crashes_and_resets_after_a_healthy_run() -> None:
    b = Backoff(first_s=0.1, max_s=0.5, healthy_after_s=10)
    assert [b.next_delay(0.0) for _ in range(5)] == [0.1, 0.2, 0.4, 0.5, 0.5]
    assert b.next_delay(11.0) == 0.1


def test_a_death_is_learnt_from_the_pidfd_without_sigchld(tmp_path: Path) -> None:
    log = tmp_path / "log"
    sup = Supervisor([serving(log, "a")])
    try:
        sup.start()
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)  # no SIGCHLD wake-up: the pidfd alone
        pid = sup.pid("a")
        assert pid is not None
        killed = time.monotonic()
        os.kill(pid, signal.SIGKILL)
        running = sup._running["a"]  # the record the pidfd event fills in
        deadline = time.monotonic() + 30
        while running.exited_at is None and time.monotonic() < deadline:
            sup._poll(1.0)  # events only: no waitpid poll here
        assert running.exited_at is not None and killed <= running.exited_at
        wait_for(lambda: sup.is_ready("a") and sup.pid("a") != pid, sup)
        assert sup.restarts["a"] == 1
        assert sup.recoveries["a"] and sup.recoveries["a"][0] > 0
    finally:
        sup.stop()
