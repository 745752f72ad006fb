"""Recording a live display: frames placed on show time, the drum track muxed in afterwards."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import av
import numpy as np
import pytest
from sf2_writer import write_sf2

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.clock import MonotonicClock
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind, Onset
from services.display.context import DisplayError
from services.display.record import (
    LiveRecorder,
    Timing,
    mux_audio,
    recording_track,
    timing_path,
)
from services.display.surface import HeadlessSurface
from services.display.video import VideoSettings, VideoWriter
from services.input.journal import JournalWriter

FPS = 25
SIZE = (160, 90)


pytestmark = pytest.mark.usefixtures("gl_ok")  # every test here draws


def test_frames_keep_show_time_and_the_drum_track_lines_up(tmp_path: Path) -> None:
    surface = HeadlessSurface(load_kit("rock5"), SIZE, "front")
    video = tmp_path / "live.mp4"
    rec = LiveRecorder(video, VideoSettings(size=SIZE, fps=FPS))
    show0 = 1000.0
    # frames as a busy live loop renders them: on time, late by three frames, then twice
    # for one grid slot
    shows = [show0 + k / FPS for k in range(10)] + [show0 + k / FPS for k in (13, 14)]
    shows += [show0 + 14.4 / FPS, show0 + 15 / FPS]
    try:
        for s in shows:
            surface.draw(None, s)
            rec.add(surface.renderer, s)
        timing = rec.close()
    finally:
        surface.close()
    assert timing == Timing.load(video) == Timing(show0, FPS, 16)
    assert (rec.repeated, rec.skipped) == (3, 1)
    assert b"moof" in video.read_bytes()  # fragmented: no index growing in memory for hours

    sr = 48_000
    track = np.zeros((int(16 / FPS * sr), 2), np.float32)
    click = int(8 / FPS * sr)  # a click on frame 8
    track[click : click + 64] = 0.8
    mux_audio(video, track, sr)
    with av.open(str(video)) as c:
        assert len(list(c.decode(c.streams.video[0]))) == 16
    with av.open(str(video)) as c:
        audio = np.concatenate([f.to_ndarray() for f in c.decode(c.streams.audio[0])], axis=1)
    peak = int(np.argmax(np.abs(audio[0]))) / sr
    assert abs(peak - 8 / FPS) < 1 / FPS, "the click stays on its frame"


def test_a_bad_video_path_is_one_error(tmp_path: Path) -> None:
    with pytest.raises(DisplayError, match="does not exist"):
        LiveRecorder(tmp_path / "no" / "x.mp4", VideoSettings(size=SIZE, fps=FPS))
    with pytest.raises(DisplayError, match="no recording timing"):
        Timing.load(tmp_path / "x.mp4")


@pytest.mark.parametrize("sound", ["built-in", "soundfont"])
def test_up_videos_drum_track_stops_a_crash_the_journal_says_was_grabbed(
    sound: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from livedrummer.live.settings import Delay, ShowSettings, Sound
    from services.cli.up import add_drum_track

    soundfont = None
    if sound == "soundfont":
        pytest.importorskip(
            "fluidsynth"
        )  # tests/livedrummer/audio/test_soundfont.py fails under CI without it
        t = np.arange(3 * 48_000) / 48_000  # rings for seconds, through its note-off
        wave = 0.8 * np.cos(2 * np.pi * 440.0 * t) * np.exp(-t / 1.5)
        soundfont = write_sf2(
            tmp_path / "ringing.sf2", np.round(wave * 32767).astype("<i2"), release_s=8.0
        )
    video, frames, show0 = tmp_path / "show.mp4", 2 * FPS, 1000.0
    writer = VideoWriter(video, VideoSettings(size=SIZE, fps=FPS))
    for _ in range(frames):
        writer.write(np.zeros((SIZE[1] * 3 // 2, SIZE[0]), np.uint8))
    writer.close()
    timing_path(video).write_text(json.dumps({"show0_s": show0, "fps": FPS, "frames": frames}))
    # the session as the input daemon journals it: a GM crash on show time 1000.25, grabbed
    # (polyphonic aftertouch on its note) at 1000.75
    spec = load_note_map("general-midi").lookup(49)
    assert spec is not None
    hit = np.array(
        [
            Onset(
                show0 + 0.25, 49, 120, 9, spec.instrument, spec.zone, spec.hihat, math.nan
            ).to_record()
        ],
        ONSET_DTYPE,
    )
    grab = np.array([(show0 + 0.75, ControlKind.CHOKE, 9, 49, 127, 0)], CONTROL_DTYPE)
    sessions = tmp_path / "sessions"
    journal = JournalWriter.create({"performer": 0}, MonotonicClock(), sessions, "s1", 0.0)
    journal.append_onsets(hit, show0 + 0.25, 0)
    journal.append_controls(grab, show0 + 0.75, 0)
    journal.close()
    settings = ShowSettings(
        "general-midi",
        "rock5",
        delay=Delay(delay_s=0.030),
        sound=Sound(kit_file=None if soundfont is None else str(soundfont)),
    )
    add_drum_track(settings, video, sessions, started=0.0)
    assert "1 hits in its drum track" in capsys.readouterr().out
    with av.open(str(video)) as c:
        a = c.streams.audio[0]
        audio = np.concatenate([f.to_ndarray() for f in c.decode(a)], axis=1).T
        rate = a.rate

    def rms(lo: float, hi: float) -> float:  # on the video's time: the hit sounds at +D
        x = audio[round((lo + 0.03) * rate) : round((hi + 0.03) * rate)].astype(np.float64)
        return float(np.sqrt(np.mean(x**2)))

    before, after = rms(0.45, 0.70), rms(0.80, 1.05)  # the grab at 0.75, its fade to 0.755
    assert before > 0.005  # the crash rings up to the grab (it would for seconds) ...
    assert after < 0.02 * before, (before, after)  # ... and is silent after it


def test_a_fragmented_recording_killed_mid_show_still_plays(tmp_path: Path) -> None:
    # 900 frames of faint noise (x264 puts a keyframe every 250, so three fragments are made
    # and the first two are on the disk), the encoder thread's queue drained, then SIGKILL: no
    # close, no index written at the end (a plain MP4 would not open at all)
    video = tmp_path / "killed.mp4"
    script = f"""
import os, signal, time
import numpy as np
from services.display.video import VideoSettings, VideoWriter
w = VideoWriter({str(video)!r}, VideoSettings(size={SIZE!r}, fps={FPS}, fragmented=True))
rng = np.random.default_rng(3)
noise = [rng.integers(100, 116, ({SIZE[1] * 3 // 2}, {SIZE[0]}), np.uint8) for _ in range(5)]
for i in range(900):
    w.write(noise[i % 5])
while w._queue.qsize():  # the test's only look inside: wait for the encoder to take them all
    time.sleep(0.01)
time.sleep(0.3)
os.kill(os.getpid(), signal.SIGKILL)
"""
    done = subprocess.run(
        [sys.executable, "-c", script],
        cwd=Path(__file__).parents[3],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == -9, done.stderr[-2000:]
    frames = 0
    with av.open(str(video)) as c:
        try:
            for _ in c.decode(c.streams.video[0]):
                frames += 1
        except av.error.InvalidDataError:  # the fragment the kill cut short, as a player sees
            pass
    assert frames >= 250, frames  # every fragment that reached the disk plays


def test_a_recordings_track_is_mixed_on_disk_not_in_memory() -> None:
    from livedrummer.audio.mix import mix_onsets

    spec = load_note_map("general-midi").lookup(38)
    assert spec is not None
    hits = np.array(
        [
            Onset(t, 38, 100, 9, spec.instrument, spec.zone, spec.hihat, math.nan).to_record()
            for t in (10.1, 10.6)
        ],
        ONSET_DTYPE,
    )
    kit = load_kit("rock5")
    track = recording_track(
        hits,
        np.zeros(0, CONTROL_DTYPE),
        Timing(10.0, FPS, 2 * FPS),
        delay_s=0.03,
        kit=kit,
        note_map=load_note_map("general-midi"),
    )
    assert isinstance(track, np.memmap)  # page cache, written out under pressure
    shifted = hits.copy()
    shifted["time_s"] += 0.03 - 10.0
    np.testing.assert_array_equal(track, mix_onsets(shifted, 2.0, kit))


def test_ticks_a_loaded_loop_missed_are_scheduled_for_the_recording() -> None:
    from services.display.live import missed_ticks

    assert missed_ticks([], 1.0, 0.05, 0.04) == []
    assert missed_ticks([(1.0, 1.05)], 1.04, 0.05, 0.04) == []  # on time: nothing missed
    ticks = missed_ticks([(1.0, 1.05)], 1.161, 0.05, 0.04)  # three ticks late
    assert [round(r, 3) for r, _ in ticks] == [1.04, 1.08, 1.12]
    assert all(abs(s - r - 0.05) < 1e-12 for r, s in ticks)
