"""The practice recording's drum track: a scripted player through a real JACK server, the rig
headless with ``--video``; the MP4's own audio, read back, has an attack at each hit's show
time (its stamp + D) and at each click's, and none elsewhere."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

rtmidi = pytest.importorskip("rtmidi")
av = pytest.importorskip("av")

FUNK = "drummer1/eval_session/1_funk-groove1_138_beat_4-4.mid"
FPS = 30
D_S = 0.030  # the synth's delay the rig sets (services.cli.practice_show.SHOW_DELAY_MS)


def attacks_s(audio: np.ndarray, rate: int) -> np.ndarray:
    """Where the track's 1 ms envelope stands above everything in the 10 ms that ended 5 ms
    before it (by 0.9 in log amplitude, floored 40 dB under the peak: an attack a few ms long, the snare's, or one rising
    out of a ringing tail, counts in full; a decay never does), a burst's first such
    millisecond; seconds on the video's time. (The AAC codec spreads an attack ~4 ms early.)"""
    ms = rate // 1000
    env = np.abs(audio[: len(audio) // ms * ms]).max(axis=1).reshape(-1, ms).max(axis=1)
    # below 40 dB under the track's peak is the codec's pre-echo (it rises from silence tens
    # of ms before a click), never an attack
    log = np.log(np.maximum(env, 0.01 * env.max()))
    before = np.array([log[max(0, k - 15) : max(1, k - 5)].max() for k in range(log.size)])
    found: list[int] = []
    for k in np.flatnonzero(log - before > 0.9).tolist():
        if not found or k - found[-1] > 30:
            found.append(k)
    return np.array(found, np.float64) / 1000.0


def peak_hz(audio: np.ndarray, rate: int, at_s: float) -> float:
    """The strongest frequency in the 20 ms from ``at_s``."""
    a = round(at_s * rate)
    chunk = audio[a : a + rate // 50].mean(axis=1) * np.hanning(rate // 50)
    spectrum = np.abs(np.fft.rfft(chunk, 8 * chunk.size))
    return float(np.argmax(spectrum) * rate / (8 * chunk.size))


def test_recording_has_the_hits_and_the_click_on_show_time(
    jack_rig_server: str, groove_dir: Path, tmp_path: Path, gl_ok: None
) -> None:
    from services.display.record import Timing
    from tests.services.practice.test_practice_live import wait_port

    video = tmp_path / "practice.mp4"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env["LP_NUM_THREADS"] = "1"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "practice",
            str(groove_dir / FUNK),
            "--virtual",
            "pads",
            "--api",
            "jack",
            "--map",
            "roland-td",
            "--bars",
            "2:2",
            "--count-in",
            "1",
            "--no-sound",
            "--json",
            "--seconds",
            "40",
            "--passes",
            "1",
            "--headless",
            "--frames-dir",
            str(tmp_path / "frames"),
            "--video",
            str(video),
            "--size",
            "160x90",
            "--fps",
            str(FPS),
            "--teacher",
            "off",
            "--no-save",
            "--click-level",
            "1",
            "--port-base",
            str(20000 + (os.getpid() + 7) % 20000),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert proc.stdout is not None
        plan = json.loads(proc.stdout.readline())
        out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "player")
        out.open_port(out.get_ports().index(wait_port("pads")))
        # snares half a beat after each of the pass's clicks: a hit and a click never share
        # an attack (217 ms apart at 138 bpm)
        beat = 60.0 / plan["bpm"]
        for t in [c + beat / 2 for c in plan["clicks_s"] if c >= plan["start_s"] - 1e-6]:
            while time.monotonic() < t:
                time.sleep(0.0002)
            out.send_message([0x99, 38, 100])
        out.close_port()
        stdout, stderr = proc.communicate(timeout=90)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stderr
    assert "4 hits and the click in its drum track" in stderr, stderr
    lines = [json.loads(line) for line in stdout.splitlines()]
    stamps = np.array([ln["hit"]["time_s"] for ln in lines if "hit" in ln]) + plan["start_s"]
    assert stamps.size == 4
    timing = Timing.load(video)
    assert timing.fps == FPS
    with av.open(str(video)) as c:
        stream = c.streams.audio[0]
        rate = int(stream.rate)
        audio = np.concatenate([f.to_ndarray() for f in c.decode(stream)], axis=1).T
    assert abs(len(audio) / rate - timing.frames / FPS) < 0.05
    hits = stamps + D_S - timing.show0_s
    clicks = np.array(plan["clicks_s"]) + D_S - timing.show0_s
    clicks = clicks[clicks < timing.frames / FPS - 0.05]
    assert hits.min() > 0 and clicks.size >= 6  # the count-in's first click may be before
    want = np.sort(np.concatenate([hits, clicks]))
    got = attacks_s(audio, rate)
    # every hit and click sounds within a frame of its show time, and nothing else does
    assert got.size == want.size, (got, want)
    assert np.abs(got - want).max() < 1.0 / FPS, (got, want)
    # the clicks are the beep (1.5 kHz, accents 2.2 kHz); the hits are the kit's snare
    tones = [peak_hz(audio, rate, t) for t in clicks]
    assert all(min(abs(f - 1500.0), abs(f - 2200.0)) < 60.0 for f in tones), tones
    drums = [peak_hz(audio, rate, t) for t in hits]
    assert all(min(abs(f - 1500.0), abs(f - 2200.0)) > 100.0 for f in drums), drums
