"""End to end: ``up --demo --headless --overlay score,joints`` draws the live strips into its
frames, scrolling with the show time of each frame."""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import av
import numpy as np

from livedrummer.render.font5x7 import GLYPH_H
from livedrummer.render.overlay import HISTORY_S, LOOKAHEAD_S
from livedrummer.render.overlay_raster import BACKGROUND, strip_heights

W, H = 640, 360


def _rgb(path: Path) -> np.ndarray:
    with av.open(str(path)) as c:
        out: np.ndarray = next(iter(c.decode(video=0))).to_ndarray(format="rgb24").astype(int)
    return out


def test_up_overlay_draws_scrolling_score_and_angle_strips(tmp_path: Path) -> None:
    base = random.Random().randrange(20_000, 40_000, 20)
    frames = tmp_path / "frames"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    done = subprocess.run(
        [sys.executable, "-m", "services", "up", "--demo", "--headless", "--port-base", str(base),
         "--seconds", "4", "--overlay", "score,joints", "--frames-dir", str(frames), "--png",
         "--size", f"{W}x{H}", "--fps", "10"],
        capture_output=True, text=True, timeout=150, env=env,
        cwd=Path(__file__).resolve().parent.parent,
    )  # fmt: skip
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
