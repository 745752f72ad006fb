"""``render --start/--end``: a part of a file, in seconds or bars, with its own sound.

The positions are pure logic (:mod:`livedrummer.timeline.span`); the renders are real (EGL,
PyAV reading the video back as an independent reader).
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
from livedrummer.timeline.span import Position, parse_position, span_seconds
from services.cli import main

FPS = 20


@pytest.mark.parametrize(
    ("text", "position"),
    [("12.5", Position(12.5)), ("3s", Position(3.0)), (".5", Position(0.5)),
     ("bar5", Position(5.0, bar=True)), ("B 2", Position(2.0, bar=True))],
)  # fmt: skip
def test_positions_parse(text: str, position: Position) -> None:
    assert parse_position(text) == position


@pytest.mark.parametrize("text", ["", "abc", "-2", "bar0", "bar", "1:30"])
def test_bad_positions_say_what_is_expected(text: str) -> None:
    with pytest.raises(ValueError, match=r"expected|count from 1"):
        parse_position(text)


@pytest.fixture
def waltz(write_midi) -> Path:  # type: ignore[no-untyped-def]
    """Four bars of 3/4 at 120 bpm (1.5 s a bar), a kick on each downbeat (0, 1.5, 3, 4.5 s),
    a snare on beat 2 (0.5, 2, 3.5, 5 s)."""
    msgs: list[mido.Message] = [
        mido.MetaMessage("set_tempo", tempo=500_000, time=0),
        mido.MetaMessage("time_signature", numerator=3, denominator=4, time=0),
    ]
    for bar in range(4):
        msgs.append(
            mido.Message("note_on", channel=9, note=36, velocity=110, time=0 if bar == 0 else 480)
        )
        msgs.append(mido.Message("note_off", channel=9, note=36, velocity=0, time=240))
        msgs.append(mido.Message("note_on", channel=9, note=38, velocity=100, time=240))
        msgs.append(mido.Message("note_off", channel=9, note=38, velocity=0, time=480))
    path: Path = write_midi(msgs)
    return path


def test_bars_become_seconds_on_the_files_grid(waltz: Path) -> None:
    perf = read_midi_file(waltz, load_note_map("general-midi"))
    assert perf.grid.bars == 4
    length = perf.duration_s + 1.0
    bar = parse_position
    assert span_seconds(bar("bar2"), bar("bar3"), perf.grid, length) == (1.5, 4.5)
    assert span_seconds(bar("bar4"), None, perf.grid, length) == (4.5, length)
    # The end of the last bar is one beat past its last beat (6.0 s), inside the tail.
    assert span_seconds(None, bar("bar4"), perf.grid, length) == (0.0, 6.0)
    assert span_seconds(bar("1"), bar("100"), perf.grid, length) == (1.0, length)
    with pytest.raises(ValueError, match="outside the piece's 4 bars"):
        span_seconds(bar("bar6"), None, perf.grid, length)
    with pytest.raises(ValueError, match="not after"):
        span_seconds(bar("3"), bar("2"), perf.grid, length)


@pytest.mark.usefixtures("gl_ok")
def test_bars_render_their_frames(waltz: Path, tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    frames = tmp_path / "frames"
    code = main(
        [
            "render",
            str(waltz),
            "--frames-dir",
            str(frames),
            "--size",
            "64x36",
            "--fps",
            str(FPS),
            "--start",
            "bar2",
            "--end",
            "bar3",
        ]
    )
    assert code == 0
    assert len(list(frames.glob("*.png"))) == 3 * FPS  # bars 2-3: 3.0 s
    assert "(from 1.50 s to 4.50 s)" in capsys.readouterr().out


@pytest.mark.usefixtures("gl_ok")
def test_a_span_video_has_the_spans_sound(waltz: Path, tmp_path: Path) -> None:
    out = tmp_path / "part.mp4"
    code = main(
        [
            "render",
            str(waltz),
            "-o",
            str(out),
            "--size",
            "64x36",
            "--fps",
            str(FPS),
            "--start",
            "2.5",
            "--end",
            "4",
        ]
    )
    assert code == 0
    with av.open(str(out)) as c:
        n_frames = sum(1 for _ in c.decode(video=0))
    with av.open(str(out)) as c:
        rate = c.streams.audio[0].rate
        audio = np.concatenate([f.to_ndarray() for f in c.decode(audio=0)], axis=1).T
    assert n_frames == math.ceil(1.5 * FPS)
    assert abs(len(audio) / rate - 1.5) < 1 / FPS
    env = np.abs(audio).max(axis=1)
    # Kick at 3.0 s and snare at 3.5 s (0.5 s and 1.0 s into the part): each attack within a
    # frame of its time, and before the kick only the tail of the snare struck at 2.0 s.
    frame = rate // FPS
    for t in (0.5, 1.0):
        at = int(t * rate)
        peak = (at - frame + int(np.argmax(env[at - frame : at + frame]))) / rate
        assert abs(peak - t) < 1 / FPS, (t, peak)
        assert env[at : at + frame].max() > 2 * env[at - 3 * frame : at - frame].max(), t
    assert env[: int(0.45 * rate)].max() < 0.5 * env[int(0.5 * rate) :].max()


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["--start", "abc"], "--start 'abc': expected seconds"),
     (["--start", "bar9"], "outside the piece's 4 bars"),
     (["--start", "3", "--end", "2"], "not after")],
)  # fmt: skip
def test_bad_spans_are_one_line_errors(waltz: Path, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                       argv: list[str], message: str) -> None:  # fmt: skip
    code = main(["render", str(waltz), "-o", str(tmp_path / "x.mp4"), *argv])
    assert code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    # One line for the error; a span in bars is checked against the file, so the file's own
    # report line (the map it chose) may come first.
    assert message in lines[-1] and len(lines) <= 2, lines
    assert not (tmp_path / "x.mp4").exists()
