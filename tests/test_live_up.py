"""``livedrummer up``: the supervised pipeline starts, runs, restarts a killed stage, stops.

Runs the real launcher with ``--demo`` (the bundled groove played as if live) and no screen,
so the display writes headless frames. Skipped where no headless OpenGL context can be made.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture
def gl_ok() -> None:
    from services.display.context import DisplayError, headless_context

    try:
        headless_context().release()
    except DisplayError as exc:
        pytest.skip(str(exc))


def launch(tmp: Path, *extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    base = random.Random().randrange(20_000, 40_000, 20)
    return subprocess.Popen(
        [sys.executable, "-m", "livedrummer", "up", "--demo", "--port-base", str(base),
         "--out", str(tmp / "frames"), *extra],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=REPO,
    )  # fmt: skip


def children(pid: int) -> dict[str, int]:
    """The launcher's children by service name (from their command lines)."""
    out: dict[str, int] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid != pid:
            continue
        words = [a.decode() for a in argv]
        for name in ("input", "synth", "display"):
            if name in words:
                out[name] = int(entry.name)
    return out


def wait_running(proc: subprocess.Popen[str]) -> list[str]:
    assert proc.stdout is not None
    lines = []
    for line in proc.stdout:
        lines.append(line)
        if line.startswith("up: input, synth and display running"):
            return lines
    raise AssertionError("up never reported running:\n" + "".join(lines[-20:]))


def test_up_demo_runs_for_the_given_seconds_and_stops_cleanly(gl_ok: None, tmp_path: Path) -> None:
    proc = launch(tmp_path, "--seconds", "3")
    out, _ = proc.communicate(timeout=90)
    assert proc.returncode == 0, out[-2000:]
    assert "up: stopped (0 restarts)" in out
    frames = list((tmp_path / "frames").glob("frame_*.png"))
    assert len(frames) >= 10, out[-2000:]


def test_a_killed_synth_is_restarted_while_input_keeps_running(gl_ok: None, tmp_path: Path) -> None:
    proc = launch(tmp_path, "--seconds", "60")
    try:
        wait_running(proc)
        before = children(proc.pid)
        assert set(before) == {"input", "synth", "display"}, before
        os.kill(before["synth"], signal.SIGKILL)
        deadline = time.monotonic() + 30
        now = before
        while time.monotonic() < deadline:
            now = children(proc.pid)
            if now.get("synth") not in (None, before["synth"]):
                break
            time.sleep(0.1)  # polling another process's state, not a start-up handshake
        assert now.get("synth") not in (None, before["synth"]), "the synth was not restarted"
        assert now["input"] == before["input"], "the input daemon must keep running"
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, out[-2000:]
    assert "up: stopped (1 restarts)" in out
