"""End to end: ``up --demo --headless --overlay score,joints`` draws the live strips into its
frames, scrolling with the show time of each frame."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import av
import numpy as np
import pytest

from livedrummer.render.font5x7 import GLYPH_H
from livedrummer.render.overlay import HISTORY_S, LOOKAHEAD_S
from livedrummer.render.overlay_raster import BACKGROUND, strip_heights
from services.bench._ports import free_port, free_port_base

W, H = 640, 360


def _rgb(path: Path) -> np.ndarray:
    with av.open(str(path)) as c:
        out: np.ndarray = next(iter(c.decode(video=0))).to_ndarray(format="rgb24").astype(int)
    return out


def test_up_overlay_draws_scrolling_score_and_angle_strips(tmp_path: Path) -> None:
    base = free_port_base()
    frames = tmp_path / "frames"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--headless",
            "--port-base",
            str(base),
            "--seconds",
            "4",
            "--overlay",
            "score,joints",
            "--frames-dir",
            str(frames),
            "--png",
            "--size",
            f"{W}x{H}",
            "--fps",
            "10",
        ],
        capture_output=True,
        text=True,
        timeout=150,
        env=env,
        cwd=Path(__file__).resolve().parents[3],
    )
    assert done.returncode == 0, done.stderr[-1500:]
    records = [json.loads(line) for line in (frames / "frames.jsonl").read_text().splitlines()]
    drawn = [r for r in records if r["pose_s"] is not None]
    assert len(drawn) >= 20, done.stderr[-800:]
    heights = strip_heights(H, frozenset({"score", "joints"}))
    score_top = H - heights["score"] - heights["joints"]
    graph_top = H - heights["joints"]

    def score_marks(r: dict[str, float]) -> np.ndarray:
        """Columns of the score's lanes in its history half (right of the lane labels, left of
        the now-line) holding a note marker: the panel dims the stage to at most ~90."""
        img = _rgb(frames / f"frame_{r['frame']:06d}.png")
        lanes = img[score_top + (GLYPH_H + 6) : graph_top, 32 : W // 2 - 2]
        return np.asarray((lanes.max(axis=-1) > 100).any(axis=0))

    # the strips are there: the panel darkens the bottom of the frame, the graph has curves
    last = _rgb(frames / f"frame_{drawn[-1]['frame']:06d}.png")
    panel = last[score_top + 2 : score_top + 6, W // 2 + 20 : W // 2 + 60].reshape(-1, 3)
    assert np.abs(panel.mean(axis=0) - np.array(BACKGROUND[:3]) * BACKGROUND[3] / 255).max() < 60
    graph = last[graph_top:, : W // 2 - 2]
    assert np.count_nonzero((graph.max(axis=-1) - graph.min(axis=-1)) > 80) > 40
    # notes scroll left at the show time's pace: a later frame's markers are an earlier
    # frame's, moved by (show2 - show1) / (history + lookahead) of the width
    pairs = 0
    for a, b in zip(drawn[-12:-6], drawn[-6:], strict=True):
        m1, m2 = score_marks(a), score_marks(b)
        assert m1.any() and m2.any()
        shift = round((b["show_s"] - a["show_s"]) / (HISTORY_S + LOOKAHEAD_S) * W)
        assert shift > 0 and not np.array_equal(m1, m2)
        moved = np.zeros_like(m1)
        moved[: m1.size - shift] = m1[shift:]
        agree = np.count_nonzero(moved[:-shift] == m2[:-shift]) / (m1.size - shift)
        assert agree > 0.9, (agree, shift)
        near = moved | np.roll(moved, 1) | np.roll(moved, -1)  # a pixel of rounding
        assert np.count_nonzero(near[:-shift] & m2[:-shift]) >= 0.75 * m2[:-shift].sum()
        pairs += 1
    assert pairs == 6


GRAB = """import os, sys, av, numpy as np
c = av.open(os.environ["DISPLAY"], format="x11grab", options={"video_size": "640x360"})
np.save(sys.argv[1], next(iter(c.decode(video=0))).to_ndarray(format="rgb24"))
"""


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_keys_o_and_g_show_the_strips_in_a_live_window(tmp_path: Path) -> None:
    """A live window under Xvfb (no synth: the empty kit), grabbed from the X server before
    any key, after O (the score strip) and after G (the angle graph below it)."""
    grab = tmp_path / "grab.py"
    grab.write_text(GRAB)
    py = sys.executable
    shots = [tmp_path / f"shot{i}.npy" for i in range(3)]
    press = "timeout 30 xdotool search --sync --name '^livedrummer' key"
    script = (
        f"{py} -m services display --live --sub tcp://127.0.0.1:{free_port()} "
        f"--size {W}x{H} --aa 0 --seconds 8 --clock monotonic & sleep 4; "
        f"{py} {grab} {shots[0]}; {press} o; sleep 1; {py} {grab} {shots[1]}; "
        f"{press} g; sleep 1; {py} {grab} {shots[2]}; wait"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", f"-screen 0 {W}x{H}x24", "sh", "-c", script],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert run.returncode == 0 and all(s.exists() for s in shots), run.stderr[-1500:]
    plain, score, both = (np.load(s).astype(int) for s in shots)
    heights = strip_heights(H, frozenset({"score", "joints"}))
    alone = strip_heights(H, frozenset({"score"}))["score"]

    def changed(img: np.ndarray, top: int, bottom: int) -> float:
        return float(np.mean(np.abs(img - plain)[top:bottom].max(axis=-1) > 0))

    assert changed(score, 0, H - alone) < 0.01  # the scene is as it was ...
    assert changed(score, H - alone, H) > 0.9  # ... under the score's panel
    assert changed(both, H - heights["joints"], H) > 0.9  # and the graph's
    red = score[H - alone + 20 :, W // 2]  # the now-line
    assert (red[:, 0] > 200).all() and (red[:, 1] < 80).all()


def test_up_names_an_unknown_overlay_in_one_line_and_exits_2() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--headless",
            "--overlay",
            "score,jionts",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=Path(__file__).resolve().parents[3],
    )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "livedrummer: error: --overlay 'score,jionts': unknown overlay 'jionts' "
        "(known: score, joints)"
    ]
