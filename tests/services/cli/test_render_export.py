"""``livedrummer render``: a video read back with PyAV matches the performance, frame and sample.

PyAV here is the independent reader: the test opens the file itself and does not use the
project's own read-back helper. Small frames (160x90) keep the test fast on llvmpipe.
"""

from __future__ import annotations

import math
from pathlib import Path

import av
import mido
import numpy as np
import pytest

from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from services.cli import main

FPS = 30
TAIL_S = 0.5
# General MIDI: 36 kick, 38 snare, 42 closed hi-hat, 49 crash. 480 ticks per beat at 120 bpm.
NOTES = [(0, 36, 110), (240, 38, 100), (360, 42, 90), (600, 49, 120), (480, 36, 127)]


pytestmark = pytest.mark.usefixtures("gl_ok")  # every test here draws


@pytest.fixture
def groove(write_midi) -> Path:  # type: ignore[no-untyped-def]
    msgs: list[mido.Message] = [mido.MetaMessage("set_tempo", tempo=500_000, time=0)]
    for delta, note, vel in NOTES:
        msgs.append(mido.Message("note_on", channel=9, note=note, velocity=vel, time=delta))
        msgs.append(mido.Message("note_off", channel=9, note=note, velocity=0, time=30))
    path: Path = write_midi(msgs)
    return path


def read_back(path: Path) -> tuple[int, float, np.ndarray, int, tuple[int, int]]:
    with av.open(str(path)) as c:
        vs = c.streams.video[0]
        pts: list[float] = []
        for f in c.decode(vs):
            assert f.pts is not None and f.time_base is not None
            pts.append(float(f.pts * f.time_base))
        size = (vs.codec_context.width, vs.codec_context.height)
    with av.open(str(path)) as c:
        a = c.streams.audio[0]
        audio = np.concatenate([f.to_ndarray() for f in c.decode(a)], axis=1).T
        rate = a.rate
    return len(pts), pts[-1] + 1 / FPS, audio, rate, size


def test_video_frames_audio_and_onsets_line_up(groove: Path, tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "out.mp4"
    code = main(
        [
            "render",
            str(groove),
            "-o",
            str(out),
            "--size",
            "160x90",
            "--fps",
            str(FPS),
            "--tail",
            str(TAIL_S),
            "--camera",
            "front",
        ]
    )
    assert code == 0
    assert "wrote" in capsys.readouterr().out
    perf = read_midi_file(groove, load_note_map("general-midi"))
    expected_frames = math.ceil((perf.duration_s + TAIL_S) * FPS)
    frames, video_s, audio, rate, size = read_back(out)
    assert size == (160, 90)
    assert frames == expected_frames
    assert video_s == pytest.approx(expected_frames / FPS, abs=1e-6)
    audio_s = len(audio) / rate
    assert abs(audio_s - video_s) < 1 / FPS
    # Each onset's attack: the loudest moment of the track near it is within one frame.
    env = np.abs(audio).max(axis=1)
    frame_n = int(rate / FPS)
    for t in perf.onsets["time_s"]:
        start = int(t * rate)
        window = env[max(0, start - frame_n) : start + frame_n]
        peak_at = (max(0, start - frame_n) + int(np.argmax(window))) / rate
        assert abs(peak_at - t) < 1 / FPS, (t, peak_at)
        quiet_before = env[max(0, start - 3 * frame_n) : max(0, start - frame_n)]
        if quiet_before.size and t > 0.1:
            # A real attack: louder than the tail of what came before.
            assert window.max() > 1.2 * quiet_before[-frame_n // 2 :].max()
    assert env[: int(perf.onsets["time_s"][0] * rate)].max(initial=0) < 0.01


def choked_crash(write_midi) -> Path:  # type: ignore[no-untyped-def]
    """A GM crash at 0.25 s, grabbed (polyphonic aftertouch 127) at 0.75 s, let go at 1.0 s."""
    msgs: list[mido.Message] = [
        mido.MetaMessage("set_tempo", tempo=500_000, time=0),
        mido.Message("note_on", channel=9, note=49, velocity=120, time=240),
        mido.Message("note_off", channel=9, note=49, velocity=0, time=30),
        mido.Message("polytouch", channel=9, note=49, value=127, time=450),
        mido.Message("polytouch", channel=9, note=49, value=0, time=240),
    ]
    path: Path = write_midi(msgs, name="choke.mid")
    return path


def crash_rms_around_the_grab(audio: np.ndarray, rate: int) -> tuple[float, float]:
    """RMS of the track 50-300 ms before and after :func:`choked_crash`'s grab (AAC's priming
    and the 5 ms fade stay out of both windows)."""

    def rms(a: float, b: float) -> float:
        x = audio[round(a * rate) : round(b * rate)].astype(np.float64)
        return float(np.sqrt(np.mean(x**2)))

    return rms(0.45, 0.70), rms(0.80, 1.05)


def test_a_choked_crash_stops_sounding_in_the_video(write_midi, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "out.mp4"
    code = main(
        [
            "render",
            str(choked_crash(write_midi)),
            "-o",
            str(out),
            "--size",
            "96x54",
            "--fps",
            "10",
            "--tail",
            "1.0",
            "--camera",
            "front",
        ]
    )
    assert code == 0
    _frames, _video_s, audio, rate, _size = read_back(out)
    before, after = crash_rms_around_the_grab(audio, rate)
    assert before > 0.01  # the crash rings up to the grab (it would for seconds) ...
    assert after < 0.02 * before, (before, after)  # ... and is silent after it


def test_a_closing_hi_hat_stops_the_open_one_ringing_in_the_video(
    write_midi, tmp_path: Path
) -> None:  # type: ignore[no-untyped-def]
    """The pedal (CC4) open, an open hi-hat at 0.25 s, the pedal closed at 0.75 s: the track
    stops ringing there, as the live sound does (the same cuts, livedrummer.audio.cuts)."""
    msgs: list[mido.Message] = [
        mido.MetaMessage("set_tempo", tempo=500_000, time=0),
        mido.Message("control_change", channel=9, control=4, value=0, time=0),
        mido.Message("note_on", channel=9, note=46, velocity=120, time=240),
        mido.Message("note_off", channel=9, note=46, velocity=0, time=30),
        mido.Message("control_change", channel=9, control=4, value=127, time=450),
        mido.Message("control_change", channel=9, control=4, value=127, time=240),
    ]
    out = tmp_path / "out.mp4"
    code = main(
        [
            "render",
            str(write_midi(msgs, name="hat.mid")),
            "-o",
            str(out),
            "--size",
            "96x54",
            "--fps",
            "10",
            "--tail",
            "1.0",
            "--camera",
            "front",
        ]
    )
    assert code == 0
    _frames, _video_s, audio, rate, _size = read_back(out)
    before, after = crash_rms_around_the_grab(audio, rate)  # the same instants
    assert before > 0.005  # the open hat rings up to the closing ...
    assert after < 0.05 * before, (before, after)  # ... and is silent after it


def test_frames_folder_gets_pngs(groove: Path, tmp_path: Path) -> None:
    frames = tmp_path / "frames"
    code = main(
        [
            "render",
            str(groove),
            "--frames-dir",
            str(frames),
            "--size",
            "96x54",
            "--fps",
            "10",
            "--tail",
            "0",
        ]
    )
    assert code == 0
    pngs = sorted(frames.glob("*.png"))
    perf = read_midi_file(groove, load_note_map("general-midi"))
    assert len(pngs) == math.ceil(perf.duration_s * 10)
    with av.open(str(pngs[3])) as c:
        img = next(iter(c.decode(video=0))).to_ndarray(format="rgb24")
    assert img.shape == (54, 96, 3)
    assert img.std() > 5  # a scene, not a blank frame


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--size", "1280x721"], "even"),
        (["--size", "big"], "WIDTHxHEIGHT"),
        (["--fps", "0"], "--fps"),
        (["--kit", "no-such-kit"], "no-such-kit"),
        (["--sticking", "no-such-strategy"], "no-such-strategy"),
    ],
)
def test_bad_options_are_one_line_errors(groove: Path, tmp_path: Path, capsys, argv: list[str],  # type: ignore[no-untyped-def]
                                         message: str) -> None:  # fmt: skip
    code = main(["render", str(groove), "-o", str(tmp_path / "x.mp4"), *argv])
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


@pytest.mark.parametrize(("name", "message"), [("x.txt", "unknown type"), ("no/x.mp4", "folder")])
def test_bad_output_is_a_one_line_error(groove: Path, tmp_path: Path, capsys, name: str,  # type: ignore[no-untyped-def]
                                        message: str) -> None:  # fmt: skip
    code = main(["render", str(groove), "-o", str(tmp_path / name), "--size", "64x36"])
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_missing_midi_file_is_an_error(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    code = main(["render", str(tmp_path / "none.mid"), "-o", str(tmp_path / "x.mp4")])
    assert code == 2
    assert "none.mid" in capsys.readouterr().err


def block_means(image: np.ndarray, blocks: int = 8) -> np.ndarray:
    """Mean RGB of each cell of a blocks x blocks grid over an (H, W, 3) image."""
    h, w = (n // blocks * blocks for n in image.shape[:2])
    cells = image[:h, :w].astype(np.float64).reshape(blocks, h // blocks, blocks, w // blocks, 3)
    means: np.ndarray = cells.mean(axis=(1, 3))
    return means


@pytest.mark.parametrize("size", ["160x96", "164x96"])
def test_video_colours_match_the_rendered_frames(groove: Path, tmp_path: Path, size: str) -> None:
    # The same frames twice: as PNGs (the renderer's RGB read-back) and as H.264 (converted to
    # I420 on the GPU; a width that is not a multiple of 8 takes the CPU conversion). PyAV
    # decodes the video back to RGB with the stream's own colour metadata; 4:2:0 and x264 blur
    # edges, so compare the mean colour of a grid of regions. CRF 12 keeps x264's own loss
    # (what this test does not measure) well under the bound: at CRF 16 the last frame of the
    # 164-wide clip came to 4.2 once the feet and footboards moved, against 2.5 at CRF 12.
    argv = [
        "render",
        str(groove),
        "--size",
        size,
        "--fps",
        "10",
        "--tail",
        "0",
        "--camera",
        "front",
        "--crf",
        "12",
    ]
    out = tmp_path / "out.mp4"
    assert main([*argv, "-o", str(out)]) == 0
    assert main([*argv, "--frames-dir", str(tmp_path / "frames")]) == 0
    pngs = sorted((tmp_path / "frames").glob("*.png"))
    with av.open(str(out)) as c:
        decoded = list(c.decode(video=0))
    assert len(decoded) == len(pngs) > 4
    for i in (0, len(pngs) // 2, len(pngs) - 1):
        frame = decoded[i]
        assert (frame.colorspace, frame.color_range) == (1, 1)  # BT.709, limited range
        video = frame.to_ndarray(format="rgb24")
        with av.open(str(pngs[i])) as c:
            rendered = next(iter(c.decode(video=0))).to_ndarray(format="rgb24")
        assert rendered.std() > 5  # a scene, not a blank frame
        want, got = block_means(rendered), block_means(video)
        assert np.abs(got - want).max() < 4.0, (i, np.abs(got - want).max())
        assert np.abs(got - want).mean() < 1.5, (i, np.abs(got - want).mean())
