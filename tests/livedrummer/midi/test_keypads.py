"""Computer keys play the kit: the layout table, the key drum's sound and glow, the mixer's
one-shots, and a real file window under Xvfb pressed with ``xdotool``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from livedrummer.kit.loader import load_kit
from livedrummer.midi.keypads import KEYPADS, LOUD, MEDIUM, RESERVED, SOFT, help_lines, keypad_hit
from livedrummer.midi.notemap import load_note_map
from livedrummer.render.body_scene import BodyScene
from livedrummer.render.hud import HELP_LINES, live_lines
from livedrummer.render.keydrum import GLOW_S, KeyDrum
from livedrummer.render.scene import CH_HIGHLIGHT, CH_WOBBLE
from services.display.audio_out import TrackRenderer

REPO = Path(__file__).resolve().parents[3]


def test_the_layout_plays_every_named_piece_on_free_keys() -> None:
    gm = load_note_map("general-midi")
    played = {
        (gm.notes[p.note].instrument, gm.notes[p.note].zone.value, gm.notes[p.note].hihat.value)
        for p in KEYPADS.values()
    }
    instruments = {i for i, _, _ in played}
    assert {"kick", "snare", "hihat", "crash1", "ride"} <= instruments
    assert sum(i.startswith("tom") for i in instruments) == 3
    assert {("hihat", h) for h in ("closed", "open", "pedal")} <= {(i, h) for i, _, h in played}
    assert ("ride", "bell") in {(i, z) for i, z, _ in played}
    assert not set(KEYPADS) & RESERVED
    assert len({p.note for p in KEYPADS.values()}) == len(KEYPADS)


def test_shift_is_loud_ctrl_soft_and_other_keys_play_nothing() -> None:
    assert keypad_hit("x") == (38, MEDIUM)
    assert keypad_hit("x", shift=True) == (38, LOUD)
    assert keypad_hit("x", ctrl=True) == (38, SOFT)
    assert keypad_hit("space") is None and keypad_hit("r") is None
    assert SOFT < MEDIUM < LOUD <= 127


def test_the_help_shows_every_key() -> None:
    text = " ".join(help_lines())
    for pad in KEYPADS.values():
        assert f"{pad.key.upper()} {pad.label}" in text
    assert help_lines()[-1] == HELP_LINES[-1]
    assert live_lines("playing", "front", True)[-1] == help_lines()[-1]
    assert help_lines()[0] not in live_lines("playing", "front", True, keys=False)


def drum() -> KeyDrum:
    return KeyDrum(load_kit("rock5"), load_note_map("general-midi"))


def test_a_key_sounds_louder_with_shift_and_lights_only_its_piece() -> None:
    d = drum()
    soft, loud = d.hit(38, MEDIUM, 10.0), d.hit(38, LOUD, 10.0)
    assert soft is not None and loud is not None and soft.shape[1] == 2
    assert np.abs(loud).max() > np.abs(soft).max() > 0.01
    snare = [p.name for p in d.kit.pieces].index("snare")
    glow = d.glow(10.0)
    assert glow[snare] == pytest.approx(LOUD / 127) and np.count_nonzero(glow) == 1
    assert d.glow(10.0 + GLOW_S)[snare] == pytest.approx(LOUD / 127 / np.e)
    assert d.glow(9.9)[snare] == 0.0  # nothing before the key
    assert d.hit(81, MEDIUM, 10.0) is None  # triangle: not on this kit / map


def test_light_raises_the_keyed_piece_in_a_scene_frame() -> None:
    from livedrummer.midi.smf import read_midi_file

    groove = next((REPO / "kits" / "grooves").glob("*.mid"))
    gm = load_note_map("general-midi")
    body = BodyScene.perform(read_midi_file(groove, gm), load_kit("rock5"), gm)
    d = KeyDrum(body.kit, gm)
    frame = body.frame_at(0.0)
    assert d.light(frame, 1.0) is frame  # no key yet
    d.hit(49, LOUD, 1.0)
    lit = d.light(frame, 1.0)
    crash = next(i for i, p in enumerate(d.kit.pieces) if p.name == d.kit.resolve("crash1").name)
    assert lit.channels[crash, CH_HIGHLIGHT] == pytest.approx(LOUD / 127)
    assert lit.channels[crash, CH_WOBBLE] >= LOUD / 127 - 1e-6
    rest = np.delete(np.arange(len(d.kit.pieces)), crash)
    np.testing.assert_array_equal(lit.channels[rest], frame.channels[rest])


def test_the_player_mixes_a_key_over_the_track_from_the_next_buffer() -> None:
    track = np.full((48000, 2), 0.1, np.float32)
    r = TrackRenderer(track, 48000)
    shot = np.ones((150, 2), np.float32)
    r.hit(shot)
    first = r.render(100, 0.0, None)  # silent track (not rolling): the key alone
    second = r.render(100, 100 / 48000, None)
    np.testing.assert_array_equal(first, np.ones((100, 2)))
    np.testing.assert_array_equal(second[:50], np.ones((50, 2)))
    np.testing.assert_array_equal(second[50:], np.zeros((50, 2)))


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_keys_in_a_real_file_window_play_pieces() -> None:
    press = "sleep 2; timeout 30 xdotool search --sync --name '^livedrummer$' key z shift+x ctrl+t space"
    script = (
        f"{sys.executable} -m services -v display --size 320x180 --aa 0 --seconds 4 & {press}; wait"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 320x180x24", "sh", "-c", script],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    played = [line.split("keys: ")[1] for line in run.stderr.splitlines() if "keys: note" in line]
    assert played == ["note 36 velocity 80", "note 38 velocity 120", "note 42 velocity 40"]


def test_every_key_reaches_a_piece_of_the_default_kit() -> None:
    d = drum()
    pieces = {p.note: d.piece_of(d.onset(p.note, MEDIUM, 0.0)) for p in KEYPADS.values()}  # type: ignore[arg-type]
    assert None not in pieces.values()
    assert len(set(pieces.values())) == 8  # kick, snare, hi-hat, 3 toms, crash, ride


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_keys_in_a_live_window_reach_the_input_daemon_as_notes(
    jack_server: str, tmp_path: Path
) -> None:
    """The live window's keys go out over a real MIDI port (JACK) into ``input --virtual``,
    which publishes them as onsets (read on its ZeroMQ stream) as a kit's pads would be."""
    import json

    import zmq

    from livedrummer import protocol as p

    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    inp = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--virtual",
            "livedrummer-keys",
            "--api",
            "jack",
            "--map",
            "general-midi",
            "--pub",
            "tcp://127.0.0.1:*",
            "--control",
            "tcp://127.0.0.1:*",
            "--no-journal",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    try:
        assert inp.stdout is not None
        info = json.loads(inp.stdout.readline())
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
        sub.connect(info["pub"])
        press = (
            "sleep 3; timeout 30 xdotool search --sync --name '^livedrummer$' key z; sleep 0.3; "
            "xdotool search --name '^livedrummer$' key shift+x; sleep 0.3; "
            "xdotool search --name '^livedrummer$' key ctrl+u; sleep 1; "
            "xdotool search --name '^livedrummer$' key q"
        )
        script = (
            f"{sys.executable} -m services -v display --live --sub tcp://127.0.0.1:9 "
            f"--size 320x180 --aa 0 --keys-port livedrummer-keys & {press}; wait"
        )
        wenv = {k: v for k, v in env.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
        win = subprocess.run(
            ["xvfb-run", "-a", "-s", "-screen 0 320x180x24", "sh", "-c", script],
            capture_output=True,
            text=True,
            timeout=120,
            env=wenv,
        )
        assert win.returncode == 0, win.stderr[-2000:]
        seen: list[tuple[int, int]] = []
        deadline = time.monotonic() + 5
        while len(seen) < 3 and time.monotonic() < deadline:
            if sub.poll(200):
                msg = p.decode(sub.recv_multipart())
                seen += [(int(r["note"]), int(r["velocity"])) for r in msg.body]
        assert seen == [(36, MEDIUM), (38, LOUD), (49, SOFT)], win.stderr[-2000:]
    finally:
        sub.close(0)
        ctx.term()
        inp.terminate()
        inp.communicate(timeout=20)


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_up_keys_plays_the_window_s_keys_into_the_pipeline(
    jack_server: str, tmp_path: Path
) -> None:
    """``up --keys`` out of the box: keys pressed in its window come out of its input daemon's
    stream as onsets (the show stops ``--seconds`` after the first frame)."""
    import socket

    import zmq

    from livedrummer import protocol as p

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        base = s.getsockname()[1] + 100
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["LIVEDRUMMER_HOME"] = str(tmp_path / "home")
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
    sub.connect(f"tcp://127.0.0.1:{base}")
    press = (
        "timeout 30 xdotool search --sync --name '^livedrummer$' >/dev/null; sleep 1; "
        "xdotool search --name '^livedrummer$' key z; sleep 0.3; "
        "xdotool search --name '^livedrummer$' key shift+x"
    )
    script = (
        f"{sys.executable} -m services up --keys --api jack --port-base {base} "
        f"--no-journal --size 320x180 --seconds 5 & {press}; wait"
    )
    try:
        up = subprocess.Popen(
            ["xvfb-run", "-a", "-s", "-screen 0 320x180x24", "sh", "-c", script],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=env,
            cwd=REPO,
        )
        seen: list[tuple[int, int]] = []
        deadline = time.monotonic() + 60
        while len(seen) < 2 and time.monotonic() < deadline and up.poll() is None:
            if sub.poll(200):
                msg = p.decode(sub.recv_multipart())
                seen += [(int(r["note"]), int(r["velocity"])) for r in msg.body]
        out, _ = up.communicate(timeout=60)
        assert seen == [(36, MEDIUM), (38, LOUD)], out[-3000:]
        assert up.returncode == 0, out[-3000:]
    finally:
        sub.close(0)
        ctx.term()


@pytest.mark.skipif(shutil.which("xvfb-run") is None or shutil.which("xdotool") is None,
                    reason="xvfb-run or xdotool not installed")  # fmt: skip
def test_a_key_in_the_file_window_is_heard_through_jack(jack_server: str, tmp_path: Path) -> None:
    """The file's only note comes after the window closes, so the one attack a JACK client
    records from the window is the key's (Shift+X, the loud snare)."""
    import mido

    from services.bench._jackrec import JackRecorder, attacks

    mid = mido.MidiFile(ticks_per_beat=480)
    mid.tracks.append(
        mido.MidiTrack(
            [
                mido.Message("note_on", note=36, velocity=100, channel=9, time=9600),  # at 10 s
                mido.Message("note_off", note=36, velocity=0, channel=9, time=10),
            ]
        )
    )
    mid.save(tmp_path / "late.mid")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    recorder = JackRecorder(env)
    press = (
        "timeout 30 xdotool search --sync --name '^livedrummer$' >/dev/null; sleep 1.5; "
        "xdotool search --name '^livedrummer$' key shift+x"
    )
    cmd = (
        f"{sys.executable} -m services -v display {tmp_path / 'late.mid'} --map general-midi "
        f"--size 320x180 --aa 0 --seconds 3.5 --audio-device 'system, JACK' & {press}; wait"
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
    assert "no sound" not in run.stderr and "keys: note 38 velocity 120" in run.stderr
    assert len(attacks(rec)) == 1, run.stderr[-1000:]
