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

LIVEDRUMMER = [
    sys.executable,
    "-c",
    "import sys; from livedrummer.cli import main; sys.exit(main())",
]
REPO = Path(__file__).resolve().parent.parent


def test_no_display_is_a_one_line_error() -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run([*LIVEDRUMMER, "display", "--quit-after", "1"], env=env, cwd=REPO,
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0
    assert "livedrummer render" in run.stderr


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_window_plays_under_xvfb() -> None:
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 640x360x24", *LIVEDRUMMER, "-v", "display",
         "--size", "640x360", "--aa", "0", "--camera", "front", "--quit-after", "1.5"],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    line = next(ln for ln in run.stderr.splitlines() if "window:" in ln)
    assert int(line.split("window:")[1].split()[0]) > 3  # frames drawn
