"""The file window's loop A-B and step size: the transport's logic, then a real window.

The transport is pure (stepped by hand); the window test plays a file under Xvfb, presses A
and B with xdotool (as a person's keys arrive) and reads the window's frame log
(``display --frame-log``): after B the shown position wraps back to A and stays inside.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from livedrummer.render.hud import hud_lines
from livedrummer.render.transport import STEPS, Transport

REPO = Path(__file__).resolve().parents[3]


def test_a_loop_wraps_forwards_and_in_reverse_carrying_the_overshoot() -> None:
    tr = Transport(duration_s=30.0)
    tr.seek(4.0)
    tr.apply("loop_start")
    assert tr.loop is None  # one end is not a loop
    tr.seek(6.0)
    tr.apply("loop_end")
    assert tr.loop == (4.0, 6.0)
    tr.apply("play_pause")
    assert tr.advance(2.5) == pytest.approx(4.5)  # 6.0 + 0.5 past B -> A + 0.5
    tr.apply("reverse")
    assert tr.advance(0.75) == pytest.approx(5.75)  # 0.25 before A -> B - 0.25
    tr.apply("loop_clear")
    tr.apply("reverse")
    assert tr.advance(1.0) == pytest.approx(6.75)  # the whole file again


def test_loop_ends_in_either_order_and_too_close_is_no_loop() -> None:
    tr = Transport(duration_s=30.0)
    tr.seek(9.0)
    tr.apply("loop_end")
    tr.seek(3.0)
    tr.apply("loop_start")
    assert tr.loop == (3.0, 9.0)
    tr.seek(12.0)
    tr.apply("loop_start")  # A after B: the two swap
    assert tr.loop == (9.0, 12.0)
    tr.seek(9.02)
    tr.apply("loop_end")  # B on A's spot: no loop until the other end moves away
    assert tr.loop is None
    tr.seek(2.0)
    tr.apply("loop_start")
    assert tr.loop == (2.0, 9.02)


def test_step_size_cycles_and_the_readout_shows_loop_and_step() -> None:
    tr = Transport(duration_s=10.0)
    seen = [tr.step_s]
    for _ in STEPS:
        tr.apply("step_size")
        seen.append(tr.step_s)
    assert seen[: len(STEPS)] == list(STEPS) and seen[-1] == STEPS[0]
    tr.apply("step_size")
    tr.seek(1.0)
    tr.apply("step_forward")
    assert tr.position_s == pytest.approx(1.010)
    lines = hud_lines(5.0, 10.0, 1.0, True, False, "stage", loop=(4.0, 6.5), step_s=0.01)
    assert lines[1] == "LOOP 0:04.0 - 0:06.5   STEP 10 MS"


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_a_and_b_loop_the_real_window(tmp_path: Path) -> None:
    log = tmp_path / "frames.jsonl"
    win = "timeout 30 xdotool search --sync --name '^livedrummer$'"
    script = (
        f"{sys.executable} -m services display --size 320x180 --aa 0 --no-sound "
        f"--seconds 9 --frame-log {log} & sleep 3; {win} key a; sleep 1.5; {win} key b; "
        "wait"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 640x360x24", "sh", "-c", script],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    shown = [json.loads(line)["t"] for line in log.read_text().splitlines()]
    back = [i for i in range(1, len(shown)) if shown[i] < shown[i - 1] - 0.2]
    assert back, "the position never wrapped back to A"
    a_s = shown[back[0]]  # the first frame after the wrap: A (plus the overshoot)
    after = shown[back[0] :]
    b_s = max(after)
    assert 0.5 < b_s - a_s < 4.0, (a_s, b_s)  # about the 1.5 s between the two key presses
    assert min(after) >= a_s - 0.1  # it stays in the loop
