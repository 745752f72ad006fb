"""Mouse orbit, zoom and pan (pure maths) and the stored viewpoints; then a real window under
Xvfb, dragged and scrolled with ``xdotool``, storing a viewpoint that a second run recalls."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.kit.loader import load_kit
from livedrummer.render.camera import Camera, kit_cameras
from livedrummer.render.orbit import (
    MAX_ELEVATION_RAD,
    MIN_DISTANCE_M,
    ZOOM_PER_NOTCH,
    ViewpointError,
    Viewpoints,
    orbit,
    pan,
    zoom,
)

REPO = Path(__file__).resolve().parents[3]
KIT = load_kit("rock5")
FRONT = kit_cameras(KIT)["front"]
W, H = 800, 450


def pixel(cam: Camera, point: np.ndarray) -> np.ndarray:
    clip = np.r_[point, 1.0] @ cam.view_projection(W / H).T.astype(np.float64)
    return np.array([(clip[0] / clip[3] + 1) / 2 * W, (1 - clip[1] / clip[3]) / 2 * H])


def rel(cam: Camera) -> np.ndarray:
    return np.asarray(cam.eye) - np.asarray(cam.target)


def test_orbit_turns_the_eye_about_the_target() -> None:
    turned = orbit(FRONT, 100.0, 0.0, H)
    assert turned.target == FRONT.target
    assert np.linalg.norm(rel(turned)) == pytest.approx(np.linalg.norm(rel(FRONT)))
    az0 = math.atan2(rel(FRONT)[1], rel(FRONT)[0])
    az1 = math.atan2(rel(turned)[1], rel(turned)[0])
    assert az1 - az0 == pytest.approx(-math.pi * 100 / H)
    assert rel(turned)[2] == pytest.approx(rel(FRONT)[2])  # a sideways drag keeps the height
    up = orbit(FRONT, 0.0, 10 * H, H)  # far past the pole: clamped
    assert math.asin(rel(up)[2] / np.linalg.norm(rel(up))) == pytest.approx(MAX_ELEVATION_RAD)
    back = orbit(orbit(FRONT, 37.0, -12.0, H), -37.0, 12.0, H)
    np.testing.assert_allclose(back.eye, FRONT.eye, atol=1e-9)


def test_zoom_moves_along_the_view_within_limits() -> None:
    near = zoom(FRONT, 2)
    ratio = np.linalg.norm(rel(near)) / np.linalg.norm(rel(FRONT))
    assert ratio == pytest.approx(ZOOM_PER_NOTCH**2)
    np.testing.assert_allclose(np.cross(rel(near), rel(FRONT)), 0.0, atol=1e-9)
    assert np.linalg.norm(rel(zoom(FRONT, 500))) == pytest.approx(MIN_DISTANCE_M)


def test_pan_keeps_the_point_under_the_cursor() -> None:
    moved = pan(FRONT, 40.0, -25.0, H)
    shift = np.asarray(moved.eye) - np.asarray(FRONT.eye)
    np.testing.assert_allclose(np.asarray(moved.target) - np.asarray(FRONT.target), shift)
    # the old target, at the centre before, is now where the cursor went: 40 right, 25 up
    np.testing.assert_allclose(
        pixel(moved, np.asarray(FRONT.target)), [W / 2 + 40.0, H / 2 - 25.0], atol=1e-6
    )


def test_viewpoints_round_trip_and_bad_files_are_named(tmp_path: Path) -> None:
    path = tmp_path / "home" / "viewpoints.json"
    assert Viewpoints.load(path).slots == {}
    vp = Viewpoints()
    vp.store(3, orbit(FRONT, 50.0, 20.0, H))
    vp.store(8, FRONT)
    vp.save(path)
    back = Viewpoints.load(path)
    assert sorted(back.slots) == [3, 8]
    assert back.recall(3) == vp.recall(3) and back.recall(1) is None
    data = json.loads(path.read_text())
    for bad, field in (
        ("{", "not JSON"),
        (json.dumps({"version": 2, "viewpoints": {}}), "version"),
        (json.dumps({"version": 1, "viewpoints": {"9": data["viewpoints"]["3"]}}), "viewpoints.9"),
        (
            json.dumps(
                {"version": 1, "viewpoints": {"3": {**data["viewpoints"]["3"], "eye": [0, "x", 1]}}}
            ),
            "3.eye",
        ),
        (
            json.dumps(
                {"version": 1, "viewpoints": {"3": {**data["viewpoints"]["3"], "fov_deg": 400}}}
            ),
            "fov_deg",
        ),
    ):
        path.write_text(bad)
        with pytest.raises(ViewpointError, match=field) as err:
            Viewpoints.load(path)
        assert str(path) in str(err.value)
    with pytest.raises(ViewpointError, match="slot 0"):
        Viewpoints().store(0, FRONT)


def _window(home: Path, shot: Path, xdo: str, seconds: float = 5.0) -> None:
    script = (
        f"{sys.executable} -m services display --size {W}x{H} --aa 0 --camera front "
        f"--seconds {seconds} --screenshot {shot} & sleep 2; "
        f"W=$(timeout 30 xdotool search --sync --name '^livedrummer$' | head -1); {xdo}; wait"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["LIVEDRUMMER_HOME"] = str(home)
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", f"-screen 0 {W}x{H}x24", "sh", "-c", script],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
    )
    assert run.returncode == 0 and shot.exists(), run.stderr[-2000:]


def _grey(png: Path) -> np.ndarray:
    import av

    with av.open(str(png)) as c:
        img = next(c.decode(video=0)).to_ndarray(format="rgb24").astype(np.float64)
    g = img.mean(axis=2)
    blocks: np.ndarray = g[: H // 10 * 10, : W // 10 * 10].reshape(H // 10, 10, W // 10, 10)
    return blocks.mean(axis=(1, 3))


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_a_dragged_view_is_stored_and_recalled_in_a_real_window(tmp_path: Path) -> None:
    home = tmp_path / "home"
    drag = (
        "xdotool mousemove --window $W 390 225 mousemove --window $W 400 225 mousedown 1 "
        "mousemove --window $W 480 225 mousemove --window $W 560 205 mouseup 1 click 4 click 4; "
        "sleep 0.5; xdotool key --window $W shift+3"
    )
    _window(home, tmp_path / "dragged.png", drag)
    stored = Viewpoints.load(home / "viewpoints.json").recall(3)
    assert stored is not None
    # the left drag turned the kit with the cursor (the eye swung to its own left, +x, seen from
    # the front) and the wheel brought it nearer
    assert stored.target == pytest.approx(FRONT.target)
    assert stored.eye[0] > FRONT.eye[0] + 0.5
    assert np.linalg.norm(rel(stored)) < np.linalg.norm(rel(FRONT)) * 0.95
    # a new run recalls it with 3: the picture is the stored view, not the front camera's
    _window(home, tmp_path / "recalled.png", "xdotool key --window $W 3")
    _window(home, tmp_path / "front.png", ":", seconds=3.0)
    dragged, recalled, front = (
        _grey(tmp_path / f"{n}.png") for n in ("dragged", "recalled", "front")
    )
    assert np.abs(recalled - dragged).mean() < 0.5 * np.abs(recalled - front).mean()
