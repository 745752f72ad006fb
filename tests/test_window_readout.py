"""The window's readout and key help: pure lines, then pixels of a real window under Xvfb.

The lines are tested as values; the window test opens the real GLFW window on a virtual X
server (``xvfb-run``), presses keys in it with ``xdotool`` (the X test extension, as a person's
keyboard would) and reads the pixels of the last frame it drew (``display --screenshot``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.render.hud import HELP_LINES, TEXT_RGBA, hud_image, hud_lines, live_lines

REPO = Path(__file__).resolve().parent.parent


def test_the_readout_says_where_how_and_when_it_ends() -> None:
    lines = hud_lines(12.44, 88.5, 0.5, True, False, "front")
    assert lines == ["0:12.4 / 1:28.5   0.5X   PLAYING   CAMERA FRONT   H HELP"]
    ended = hud_lines(88.5, 88.5, 1.0, False, False, "stage")
    assert "PAUSED" in ended[0] and ended[1].startswith("END OF FILE")
    helped = hud_lines(3.0, 88.5, 1.0, True, True, "stage", show_help=True)
    assert "REVERSE" in helped[0] and helped[-len(HELP_LINES) :] == list(HELP_LINES)
    assert live_lines("waiting for poses", "stage")[0].startswith("LIVE   WAITING FOR POSES")


def test_the_readout_image_is_text_on_a_translucent_panel() -> None:
    img = hud_image(["0:01.0 / 0:02.0"])
    lit = np.all(img == TEXT_RGBA, axis=2)
    assert lit.sum() > 50 and (img[..., 3][~lit] < 255).all()


def text_rows(png: Path, left: int = 8, width: int = 500) -> np.ndarray:
    """Rows of the frame's top-left region holding readout text (the font's near-white)."""
    import av

    with av.open(str(png)) as c:
        frame = next(c.decode(video=0)).to_ndarray(format="rgb24")
    region = frame[:, left : left + width].astype(int)
    return np.flatnonzero((region >= 225).all(axis=2).sum(axis=1) > 3)


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_h_shows_the_key_help_in_a_real_window(tmp_path: Path) -> None:
    shots = {}
    for keys in ("", "h"):
        shot = tmp_path / f"shot{keys or 'none'}.png"
        press = f"sleep 2; xdotool search --sync --name '^livedrummer$' key {keys}" if keys else ":"
        script = (f"{sys.executable} -m services display --size 800x450 --aa 0 --camera front "
                  f"--seconds 4 --screenshot {shot} & {press}; wait")  # fmt: skip
        env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
        run = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 800x450x24", "sh", "-c", script],
                             cwd=REPO, capture_output=True, text=True, timeout=180, env=env)  # fmt: skip
        assert run.returncode == 0 and shot.exists(), run.stderr[-2000:]
        shots[keys] = text_rows(shot)
    plain, helped = shots[""], shots["h"]
    # one readout line at the top (a highlight or two of the scene may be as bright below)
    assert 10 <= plain[plain < 40].size and plain[plain >= 40].size <= 4
    assert helped[helped >= 40].size >= 40  # the help's seven lines below it
