"""The file window plays its drum track: the sample-level player alone, then a real window under
Xvfb sounding through a real JACK server, recorded by a JACK client and compared with the
frames the window drew."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import mido
import numpy as np
import pytest

from services.display.audio_out import FADE_S, Request, TrackRenderer, muted_reason

REPO = Path(__file__).resolve().parents[3]
SR = 48_000


def ramp_track(n: int = SR) -> np.ndarray:
    """A track whose sample i is i / n on both channels: a position can be read off a value."""
    x = (np.arange(n, dtype=np.float32) / n)[:, None]
    return np.repeat(x, 2, axis=1)


def play(
    r: TrackRenderer, request: Request | None, start_dac: float, blocks: int, n: int = 64
) -> np.ndarray:
    return np.concatenate([r.render(n, start_dac + k * n / SR, request) for k in range(blocks)])


def test_the_sample_heard_at_a_time_is_the_one_of_the_position_then() -> None:
    track = ramp_track()
    r = TrackRenderer(track, SR)
    req = Request(position_s=0.25, at=10.0, rolling=True)
    # the first buffer reaches the speakers 0.1 s after the request: position 0.35 s then
    out = play(r, req, 10.1, 40)
    fade = round(FADE_S * SR)
    start = round(0.35 * SR)
    assert np.allclose(out[fade:, 0], track[start + fade : start + 40 * 64, 0])
    assert np.all(np.abs(np.diff(out[:, 0])) < 1.0 / fade + 1e-3)  # faded in, no step


def test_it_plays_on_and_jumps_only_when_the_transport_jumps() -> None:
    r = TrackRenderer(ramp_track(), SR)
    play(r, Request(0.0, 0.0, True), 0.0, 10)
    # the same course read a little late (5 ms: jitter, not a seek): no jump
    play(r, Request(0.5 * 64 * 10 / SR + 0.005, 64 * 10 / SR, True), 64 * 10 / SR, 5)
    assert r.jumps == 1
    out = play(r, Request(0.8, 64 * 15 / SR, True), 64 * 15 / SR, 20)  # a seek to 0.8 s
    assert r.jumps == 2
    assert abs(out[-1, 0] - (0.8 + (20 * 64 - 1) / SR)) < 1e-4
    assert np.max(np.abs(np.diff(out[:, 0]))) < 0.8 / round(FADE_S * SR) + 1e-3  # a crossfade
    paused = play(r, Request(0.9, 64 * 35 / SR, False), 64 * 35 / SR, 10)
    assert np.all(paused[round(FADE_S * SR) :] == 0) and r.pos is None
    assert np.max(np.abs(np.diff(paused[:, 0]))) < 1.0 / round(FADE_S * SR) + 1e-3  # faded out


def test_other_speeds_and_reverse_are_muted_and_say_so() -> None:
    assert muted_reason(True, 1.0, False) is None
    assert muted_reason(False, 0.5, True) is None  # paused: nothing to say
    assert muted_reason(True, 0.5, False) == "sound muted at 0.5x"
    assert muted_reason(True, 1.0, True) == "sound muted in reverse"


HITS = [1.6, 2.2, 2.8, 3.4, 4.0]  # from 1.6 s: the start-up (first frames, first writes) settled


def hits_file(path: Path) -> Path:
    """Kick and snare alternating at HITS (120 bpm, 480 ticks a beat)."""
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    mid.tracks.append(track)
    last = 0
    for k, t in enumerate(HITS):
        tick = round(t * 960)
        note = 36 if k % 2 == 0 else 38
        track.append(mido.Message("note_on", note=note, velocity=110, channel=9, time=tick - last))
        track.append(mido.Message("note_off", note=note, velocity=0, channel=9, time=10))
        last = tick + 10
    mid.save(path)
    return path


def picture_times(log: Path, onsets: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Shared-clock times at which the window's frames reached each onset (interpolated between
    the two frames around it), and the length of that frame interval: a contact is on screen
    in one of those two frames, so that is what "within one frame" allows."""
    rows = [json.loads(line) for line in log.read_text().splitlines()]
    mono = np.array([r["mono"] for r in rows])
    t = np.array([r["t"] for r in rows])
    moving = np.concatenate([[True], np.diff(t) > 0])
    mono, t = mono[moving], t[moving]
    k = np.clip(np.searchsorted(t, onsets), 1, len(t) - 1)
    return np.interp(onsets, t, mono), mono[k] - mono[k - 1]


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_the_window_sounds_each_hit_with_the_frame_that_shows_it(
    jack_server: str, tmp_path: Path
) -> None:
    from services.bench._jackrec import JackRecorder, attacks

    midi, log = hits_file(tmp_path / "hits.mid"), tmp_path / "frames.jsonl"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    recorder = JackRecorder(env)
    cmd = (
        f"{sys.executable} -m services display {midi} --map general-midi --size 320x180 "
        f"--aa 0 --seconds 5.5 --audio-device 'system, JACK' --frame-log {log}"
    )
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 320x180x24", "sh", "-c", cmd],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
    )
    rec = recorder.stop()
    assert run.returncode == 0, run.stderr[-2000:]
    assert "no sound" not in run.stderr and rec.sources, run.stderr[-2000:]
    heard = attacks(rec)
    assert len(heard) == len(HITS), (heard, run.stderr[-1000:])
    seen, frame_s = picture_times(log, HITS)
    gap = heard - seen
    assert np.all(np.abs(gap) <= frame_s), (gap, frame_s)


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_with_no_sound_output_the_window_plays_silently_and_says_so_once(tmp_path: Path) -> None:
    log = tmp_path / "frames.jsonl"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    cmd = (
        f"{sys.executable} -m services display {hits_file(tmp_path / 'h.mid')} --map "
        f"general-midi --size 160x90 --aa 0 --seconds 1.5 --audio-device no-such-output "
        f"--frame-log {log}"
    )
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 160x90x24", "sh", "-c", cmd],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    said = [line for line in run.stderr.splitlines() if "no sound" in line]
    assert len(said) == 1 and "no-such-output" in said[0] and "monotonic" in said[0], run.stderr
    t = [json.loads(line)["t"] for line in log.read_text().splitlines()]
    assert t[-1] > 0.5  # it played on the monotonic clock
