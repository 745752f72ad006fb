"""``livedrummer up``: the supervised pipeline starts, runs, restarts a killed stage, stops.

Runs the real launcher with ``--demo`` (the bundled groove played as if live) and no screen,
so the display writes headless frames. Skipped where no headless OpenGL context can be made.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from services.bench._faultrig import children
from services.bench._ports import free_port_base

REPO = Path(__file__).resolve().parents[3]


def launch(tmp: Path, *extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    base = free_port_base()
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--port-base",
            str(base),
            "--frames-dir",
            str(tmp / "frames"),
            *extra,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        cwd=REPO,
    )


def wait_running(proc: subprocess.Popen[str]) -> list[str]:
    assert proc.stdout is not None
    lines = []
    for line in proc.stdout:
        lines.append(line)
        if line.startswith("up: input, synth and display running"):
            return lines
    raise AssertionError("up never reported running:\n" + "".join(lines[-20:]))


def test_up_demo_runs_for_the_given_seconds_and_stops_cleanly(gl_ok: None, tmp_path: Path) -> None:
    proc = launch(tmp_path, "--seconds", "3", "--png")
    out, _ = proc.communicate(timeout=90)
    assert proc.returncode == 0, out[-2000:]
    assert "up: stopped (0 restarts)" in out
    frames = list((tmp_path / "frames").glob("frame_*.png"))
    assert len(frames) >= 10, out[-2000:]  # PNGs only when asked for (--png) ...
    logged = (tmp_path / "frames" / "frames.jsonl").read_text().splitlines()
    assert len(logged) == len(frames)


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
    # ... and not by default: a headless show logs its frames but fills no disk with images
    assert (tmp_path / "frames" / "frames.jsonl").exists()
    assert not list((tmp_path / "frames").glob("frame_*.png"))


def test_up_records_the_show_with_its_drum_track_on_show_time(gl_ok: None, tmp_path: Path) -> None:
    import av
    import numpy as np
    import zmq

    from livedrummer import protocol as p
    from services.display.record import Timing

    video = tmp_path / "show.mp4"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    base = free_port_base()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--port-base",
            str(base),
            "--frames-dir",
            str(tmp_path / "frames"),
            "--seconds",
            "6",
            "--video",
            str(video),
            "--size",
            "320x180",
            "--fps",
            "25",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        cwd=REPO,
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(f"tcp://127.0.0.1:{base}")  # the input daemon's events
    stamps: list[float] = []
    try:
        while proc.poll() is None:
            if sub.poll(100):
                msg = p.decode(sub.recv_multipart())
                if msg.kind is p.Kind.ONSET and isinstance(msg.body, np.ndarray):
                    stamps.extend(msg.body["time_s"].astype(float).tolist())
        out = proc.stdout.read() if proc.stdout else ""
    finally:
        sub.close(0)
        ctx.term()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, out[-2000:]
    assert "wrote" in out and "hits in its drum track" in out, out[-2000:]
    # a set-length recording is drawn after the show, every frame (none repeated for lack of CPU)
    assert "display: drawing the recording" in out and "recording repeats" not in out
    timing = Timing.load(video)
    with av.open(str(video)) as c:
        frames = len(list(c.decode(c.streams.video[0])))
    with av.open(str(video)) as c:
        a = c.streams.audio[0]
        audio = np.concatenate([f.to_ndarray() for f in c.decode(a)], axis=1).T
        rate = a.rate
    assert frames == timing.frames and 0.7 * 6 * 25 < frames <= 6 * 25 + 2
    assert abs(len(audio) / rate - frames / 25) < 0.05
    # the hits heard by this test's own subscriber sound at onset + D on the video's time:
    # the track's onset strength (rise of the log envelope, 1 ms bins) correlates best with
    # those hits at a lag within one frame
    ms = rate // 1000
    env_a = np.abs(audio[: len(audio) // ms * ms]).max(axis=1).reshape(-1, ms).max(axis=1)
    rise = np.maximum(np.diff(np.log(env_a + 1e-4)), 0.0)
    heard = np.array([t + 0.030 - timing.show0_s for t in stamps])
    heard = heard[(heard > 0.25) & (heard < frames / 25 - 0.25)]
    assert heard.size >= 10
    lags = np.arange(-200, 201)
    score = [rise[np.round(heard * 1000).astype(int) + lag - 1].sum() for lag in lags]
    best = int(lags[int(np.argmax(score))])
    assert abs(best) < 1000 / 25, f"drum track {best} ms off the show"
    assert max(score) > 3 * float(np.median(score)), "the hits are not where the track rises"


@pytest.mark.parametrize("source", [["--keys", "--api", "jack"], ["--audio", "system"]],
                         ids=["keys", "audio"])  # fmt: skip
def test_up_gives_every_child_the_one_map_and_delay_it_resolved(
    gl_ok: None, jack_server: str, tmp_path: Path, source: list[str]
) -> None:
    # --keys and --audio play General MIDI notes: the map up checks its source with, gives
    # its children and mixes a recording with, read back from each child's ready line
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            *source,
            "--headless",
            "--no-journal",
            "--port-base",
            str(free_port_base()),
            "--frames-dir",
            str(tmp_path / "frames"),
            "--delay-ms",
            "45",
            "--lookahead-ms",
            "20",
            "--seconds",
            "3",
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    ready = {}
    for line in proc.stdout.splitlines():
        if line.startswith("{"):
            said = json.loads(line)
            ready[said["service"]] = said["settings"]
    assert set(ready) == {"input", "synth", "display"}, proc.stdout
    for name, settings in ready.items():
        assert settings["map"] == "general-midi", name
        assert settings["kit"] == "rock5", name
        assert (settings["delay_ms"], settings["lookahead_ms"]) == (45.0, 20.0), name
    assert len({s["digest"] for s in ready.values()}) == 1, ready


def test_up_refuses_a_map_that_audio_does_not_write(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "services", "up", "--audio", "system", "--map", "roland-td"],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
        env={**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")},
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        "livedrummer: error: --map roland-td: --audio writes general-midi notes; drop --map"
    ], proc.stderr
