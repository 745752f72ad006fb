"""The window, smoke-tested under a virtual X server when ``xvfb-run`` is installed.

The transport and key logic are tested without a window in test_render_motion.py; this only
proves the GLFW window, its context and the draw loop work, and that no display is a clean
one-line error.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from services.bench._ports import free_port_base

LIVEDRUMMER = [
    sys.executable,
    "-c",
    "import sys; from services.cli import main; sys.exit(main())",
]
REPO = Path(__file__).resolve().parents[3]


def test_no_display_is_a_one_line_error() -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run(
        [*LIVEDRUMMER, "display", "--seconds", "1"],
        env=env,
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0
    assert "livedrummer render" in run.stderr


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_window_plays_under_xvfb() -> None:
    run = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x360x24",
            *LIVEDRUMMER,
            "-v",
            "display",
            "--size",
            "640x360",
            "--aa",
            "0",
            "--camera",
            "front",
            "--seconds",
            "1.5",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    line = next(ln for ln in run.stderr.splitlines() if "window:" in ln)
    assert int(line.split("window:")[1].split()[0]) > 3  # frames drawn


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_live_display_draws_in_a_window_under_xvfb() -> None:
    # no synth is running: the live window still draws the kit, frame after frame
    run = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x360x24",
            *LIVEDRUMMER,
            "display",
            "--live",
            "--sub",
            "tcp://127.0.0.1:1",
            "--size",
            "320x180",
            "--aa",
            "0",
            "--max-frames",
            "12",
            "--fps",
            "30",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert "display: 12 frames" in run.stderr


def test_live_window_refuses_recording_options(tmp_path: Path) -> None:
    run = subprocess.run(
        [*LIVEDRUMMER, "display", "--live", "--video", str(tmp_path / "a.mp4")],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    assert "--headless" in run.stderr and "Traceback" not in run.stderr


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_up_opens_the_live_window_where_there_is_a_screen(tmp_path: Path) -> None:

    base = free_port_base()
    run = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x360x24",
            *LIVEDRUMMER,
            "up",
            "--demo",
            "--seconds",
            "4",
            "--port-base",
            str(base),
            "--size",
            "320x180",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")},
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "running; in a window" in run.stdout
    line = next(ln for ln in run.stderr.splitlines() if ln.startswith("display: "))
    assert int(line.split()[1]) > 30, line  # frames drawn in the window
    assert "(0 lost upstream)" in run.stderr
