"""Recording a live display: frames placed on show time, the drum track muxed in afterwards."""

from __future__ import annotations

from pathlib import Path

import av
import numpy as np
import pytest

from livedrummer.kitfile import load_kit
from services.display.context import DisplayError
from services.display.record import LiveRecorder, Timing, mux_audio
from services.display.surface import HeadlessSurface
from services.display.video import VideoSettings

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
