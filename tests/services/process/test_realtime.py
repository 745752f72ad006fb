"""Real-time scheduling for the input daemon: granted where permitted, never fatal."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
PROBE = """
import os, sys
from services.process.realtime import request_realtime
got = request_realtime(int(sys.argv[1]), "probe")
print(got, os.sched_getscheduler(0) == os.SCHED_FIFO, os.sched_getparam(0).sched_priority)
"""


def test_the_policy_is_what_was_granted() -> None:
    # in a child process: the test runner itself must not run at a FIFO priority
    run = subprocess.run(
        [sys.executable, "-c", PROBE, "12"], cwd=REPO, capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 0, run.stderr
    granted, fifo, priority = run.stdout.split()
    assert granted == fifo
    if granted == "True":
        assert priority == "12"
    else:
        assert "no real-time scheduling" in run.stderr


@pytest.mark.skipif(os.geteuid() != 0, reason="needs the right to set SCHED_FIFO")
def test_root_gets_fifo() -> None:
    run = subprocess.run(
        [sys.executable, "-c", PROBE, "30"], cwd=REPO, capture_output=True, text=True, timeout=60
    )
    assert run.stdout.split() == ["True", "True", "30"], run.stderr


def test_a_priority_out_of_range_is_one_line() -> None:
    run = subprocess.run(
        [sys.executable, "-m", "services", "input", "--file", "x.mid", "--realtime", "99"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert "--realtime" in run.stderr and "Traceback" not in run.stderr
    assert run.stderr.strip().count("\n") == 0
