"""MIDI controllers: a learned map of faders and pads steers a running show (real JACK server,
scripted MIDI ports, ``up``'s OSC state to check)."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rtmidi

from livedrummer.live.controlmap import ControlMapError, load_control_map
from tests.services.cli.test_live_up import launch, wait_running
from tests.services.show.test_live_osc import Frames, state
from tests.services.show.test_show_rig import player, wait_port

MAP = """
[[control]]
cc = 7
channel = 1
param = "head_amplitude_deg"

[[control]]
note = 36
camera = "front"

[[control]]
note = 37
blackout = true
"""


def test_a_control_map_turns_midi_into_show_commands(tmp_path: Path) -> None:
    path = tmp_path / "show.toml"
    path.write_text(MAP)
    m = load_control_map(path)
    assert m.commands("cc", 0, 7, 127) == [("/livedrummer/param/head_amplitude_deg", (30.0,))]
    assert m.commands("cc", 0, 7, 0) == [("/livedrummer/param/head_amplitude_deg", (0.0,))]
    assert m.commands("cc", 3, 7, 64) == [], "another channel"
    assert m.commands("note", 9, 36, 100) == [("/livedrummer/camera", ("front",))]
    assert m.commands("note", 9, 36, 0) == [], "a pad's release does nothing"
    assert m.commands("note", 9, 37, 90) == [("/livedrummer/blackout", (1,))]
    assert m.commands("note", 9, 37, 90) == [("/livedrummer/blackout", (0,))], "a pad toggles"
    path.write_text(m.toml())
    assert load_control_map(path).bindings == m.bindings
    for bad, match in [
        ("[[control]]\nnote = 5\nparam = 'head_amplitude_deg'\n", "needs a controller"),
        ("[[control]]\ncc = 5\ncamera = 'zoom'\n", "expected one of stage"),
        ("[[control]]\ncc = 5\nnote = 4\ncue = 'a'\n", "one of them"),
        ("[[control]]\ncc = 500\ncue = 'a'\n", "must be <= 127"),
        ("[[control]]\ncc = 5\ncue = 'a'\ncamera = 'front'\n", "one target"),
    ]:
        path.write_text(bad)
        with pytest.raises(ControlMapError, match=match):
            load_control_map(path)


def test_learn_a_controller_then_steer_up_with_it(
    jack_server: str, gl_ok: None, tmp_path: Path
) -> None:
    out = tmp_path / "show.toml"
    learn = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "control",
            "learn",
            "--virtual",
            "learnctl",
            "--api",
            "jack",
            "-o",
            str(out),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert learn.stdin is not None and learn.stdout is not None
    surface = player(wait_port("learnctl"))
    # each control moved, and the answer typed (the first answer is wrong: asked again)
    script = [
        ([0xB0, 7, 40], ["camera nowhere", "param head_amplitude_deg"]),
        ([0x99, 36, 100], ["camera front"]),
        ([0x99, 38, 100], ["skip"]),
        ([0x99, 37, 100], ["blackout"]),
    ]
    lines: list[str] = []
    try:
        for message, answers in script:
            line = learn.stdout.readline()
            lines.append(line)
            assert line.startswith("move a control"), lines
            surface.send_message(message)
            line = learn.stdout.readline()
            lines.append(line)
            assert line.startswith("heard "), lines
            for answer in answers:
                learn.stdin.write(answer + "\n")
                learn.stdin.flush()
                lines.append(learn.stdout.readline())
        assert learn.stdout.readline().startswith("move a control")
        learn.stdin.write("\n")
        learn.stdin.flush()
        rest, err = learn.communicate(timeout=30)
    finally:
        surface.close_port()
        if learn.poll() is None:
            learn.kill()
    assert learn.returncode == 0, err
    assert "expected one of stage" in "".join(lines), "a wrong answer says what is expected"
    assert f"wrote {out}: 3 controls" in rest
    learned = load_control_map(out)
    assert [(b.kind, b.number, b.target) for b in learned.bindings] == [
        ("cc", 7, "param"),
        ("note", 36, "camera"),
        ("note", 37, "blackout"),
    ]

    # the controller: a virtual output port that up opens as its --control-midi
    ctl = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "desk")
    ctl.open_virtual_port("faders")
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    proc = launch(
        tmp_path,
        "--seconds",
        "60",
        "--osc",
        str(port),
        "--fps",
        "10",
        "--control",
        str(out),
        "--control-midi",
        "faders",
        "--api",
        "jack",
    )
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.bind(("127.0.0.1", 0))
    client.settimeout(5.0)
    frames = Frames(tmp_path / "frames")
    try:
        head = "".join(wait_running(proc))
        frames.wait(lambda r: r.get("pose_s") is not None, "with the drummer", 60.0)
        ctl.send_message([0xB0, 7, 127])  # the fader all the way up
        ctl.send_message([0x99, 36, 100])  # the front camera's pad
        frames.wait(lambda r: r.get("camera") == "front", "from the front camera")
        deadline = time.monotonic() + 5.0
        while state(client, port)["param/head_amplitude_deg"] != pytest.approx(30.0):
            assert time.monotonic() < deadline, "the fader did not reach the synth"
        ctl.send_message([0x99, 37, 100])
        frames.wait(lambda r: r.get("dark") == 1.0, "black after the blackout pad")
    finally:
        proc.terminate()
        output, _ = proc.communicate(timeout=60)
        client.close()
        ctl.close_port()
    assert proc.returncode == 0, output[-3000:]
    assert "up: controller faders steers the show" in head
