"""Cue lists: strict TOML, cues at times and bars, the style eased in at a cue, and
``render --cues`` cutting the camera and blacking out on the file's bars."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mido
import numpy as np
import pytest

from livedrummer.body.expression import Expression, load_expression
from livedrummer.body.perform import perform
from livedrummer.body.rig import Rig
from livedrummer.live.cues import CueError, cue_times, expression_at, load_cues, style_changes
from livedrummer.midi.notemap import load_note_map
from livedrummer.render.body_scene import BodyScene
from livedrummer.render.cued import CuedBodyScene
from livedrummer.timeline.performance import Performance
from tests.conftest import MidiWriter
from tests.services.show.test_live_osc import read_png

REPO = Path(__file__).resolve().parents[3]

CUES = """
[[cue]]
name = "wide"
at_s = 1.0
camera = "overhead"
cut = true

[[cue]]
name = "big"
bar = 2
preset = "energetic"
blackout = true
[cue.params]
head_amplitude_deg = 14.0

[[cue]]
name = "by-hand"
camera = 2
"""


def test_a_cue_list_loads_strictly(tmp_path: Path) -> None:
    path = tmp_path / "cues.toml"
    path.write_text(CUES)
    cues = load_cues(path)
    assert list(cues) == ["wide", "big", "by-hand"]
    assert cues["by-hand"].camera == "front" and cues["by-hand"].at_s is None
    timed = cue_times(cues, np.array([0.0, 2.0, 4.0]))
    assert [(t, c.name) for t, c in timed] == [(1.0, "wide"), (2.0, "big")]
    assert cue_times(cues, np.array([0.0]))[-1][1].name == "wide", "a bar past the end never fires"
    base = Expression()
    assert expression_at(timed, 1.5, base) == base
    after = expression_at(timed, 2.0, base)
    assert after.amplitude_gain == load_expression("energetic").amplitude_gain
    assert after.head_amplitude_deg == 14.0
    assert [t for t, _ in style_changes(timed, base)][1:] == [2.0]
    for bad, match in [
        ('[[cue]]\nname = "a"\ncamra = "front"\n', r"cue 'a'.*camra.*did you mean 'camera'"),
        ('[[cue]]\nname = "a"\ncamera = "zoom"\n', r"camera.*expected one of stage"),
        ('[[cue]]\nname = "a"\nat_s = 1\nbar = 2\n', r"at_s or bar, not both"),
        ('[[cue]]\nname = "a"\n[cue.params]\nhead_amp = 1\n', r"head_amp: no such expression"),
        ('[[cue]]\nname = "a"\npreset = "nope"\n', r"no expression preset named 'nope'"),
        ('[[cue]]\nname = "a"\n[[cue]]\nname = "a"\n', r"a second cue of that name"),
    ]:
        path.write_text(bad)
        with pytest.raises(CueError, match=match):
            load_cues(path)


def test_a_style_cue_eases_from_one_animation_to_the_other(rig: Rig, groove: Performance) -> None:
    note_map = load_note_map("roland-td")
    plain = BodyScene(rig.kit, perform(groove, rig, note_map))
    energetic = perform(
        groove, rig, note_map, load_expression("energetic"), sticking=plain.performed.sticking
    )
    cued = CuedBodyScene(rig.kit, plain.performed, ((3.0, energetic),), ramp_s=0.5)
    times = np.arange(2.0, 4.5, 1 / 240)
    rot = cued.poses(times)["rotation"]
    before, after = times < 3.0, times >= 3.5
    # bit-exact by design: before its cue the cued scene runs the plain scene's own code
    assert np.array_equal(rot[before], plain.poses(times[before])["rotation"])
    late = sample = BodyScene(rig.kit, energetic).poses(times[after])["rotation"]
    assert np.allclose(rot[after], sample, atol=1e-6) and late.size
    dot = np.abs(np.sum(rot[1:].astype(np.float64) * rot[:-1], axis=-1)).clip(0, 1)
    speed = (2 * np.arccos(dot)).max(axis=1) * 240
    ramp = (times[1:] >= 3.0) & (times[1:] <= 3.5)
    assert speed[ramp].max() <= speed[~ramp].max(), "no joint is faster during the ramp"


def test_render_fires_the_cues_at_their_times_and_bars(
    gl_ok: None, tmp_path: Path, write_midi: MidiWriter
) -> None:
    # 120 bpm, 4/4: bar 2 starts at 2.0 s; a snare on each beat, a hi-hat on each eighth
    msgs: list[mido.Message] = []
    for k in range(16):
        notes = [42] + ([38] if k % 2 == 0 else [])
        for i, n in enumerate(notes):
            msgs.append(
                mido.Message(
                    "note_on", channel=9, note=n, velocity=90, time=0 if i else 240 if k else 0
                )
            )
        for n in notes:
            msgs.append(mido.Message("note_off", channel=9, note=n, velocity=0, time=0))
    midi = write_midi(msgs)
    cues = tmp_path / "cues.toml"
    cues.write_text(CUES)
    out = tmp_path / "frames"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            str(midi),
            "--frames-dir",
            str(out),
            "--size",
            "160x90",
            "--fps",
            "10",
            "--tail",
            "0.5",
            "--cues",
            str(cues),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert "2 timed cues (1 change the style)" in run.stderr
    frame = {i: read_png(out / f"frame_{i:06d}.png").astype(int) for i in (5, 9, 11, 15, 26, 34)}
    assert np.abs(frame[9] - frame[5]).mean() < np.abs(frame[11] - frame[9]).mean() / 3, (
        "the cut at 1.0 s changes the picture more than the playing does"
    )
    assert frame[15].mean() > 5 and frame[26].max() <= 1 and frame[34].max() <= 1, (
        "black from the blackout at bar 2 (2.0 s) once its fade is over"
    )
