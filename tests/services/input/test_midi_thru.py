"""``input --thru``: what the kit sends, forwarded to another MIDI port, re-mapped for a
General MIDI sampler; through a real JACK server, stamped by the C reference client on both
ports, so the added latency is measured where JACK sees the messages."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.thrumap import gm_remap

rtmidi = pytest.importorskip("rtmidi")
REPO = Path(__file__).resolve().parents[3]


def test_a_roland_kit_is_re_mapped_to_general_midi_drums() -> None:
    remap = gm_remap(load_note_map("roland-td"))
    assert remap([0x99, 22, 100]) == [0x99, 42, 100]  # closed hi-hat edge -> GM closed hat
    assert remap([0x90, 38, 90]) == [0x99, 38, 90]  # any channel -> 10
    assert remap([0x89, 22, 0]) == [0x89, 42, 0]  # note off
    assert remap([0xB9, 4, 90]) == [0xB9, 4, 90]  # the hi-hat pedal's controller passes
    assert remap([0x99, 3, 90]) == [0x99, 3, 90]  # a note the map does not know passes


def test_thru_forwards_each_hit_remapped_and_its_latency_is_measured(
    jack_rig_server: str, tmp_path: Path
) -> None:
    from services.bench._jack import jack_env
    from services.bench.input_load import Reference, build_reference

    exe = build_reference(tmp_path)
    env = {**os.environ, **jack_env(jack_rig_server), "LIVEDRUMMER_HOME": str(tmp_path)}
    kit = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
    kit.open_virtual_port("pads")
    daemon = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--midi",
            "kit:pads",
            "--api",
            "jack",
            "--map",
            "roland-td",
            "--pub",
            "tcp://127.0.0.1:*",
            "--control",
            "tcp://127.0.0.1:*",
            "--no-journal",
            "--thru",
            "ldthru",
            "--thru-map",
            "general-midi",
        ],
        stdout=subprocess.PIPE,
        stderr=(tmp_path / "input.err").open("w"),
        text=True,
        env=env,
        cwd=REPO,
    )
    refs = []
    try:
        assert daemon.stdout is not None and daemon.stdout.readline(), (
            tmp_path / "input.err"
        ).read_text()
        ports = subprocess.run(["jack_lsp"], capture_output=True, text=True, env=env).stdout
        thru_port = next(p for p in ports.splitlines() if p.endswith(":ldthru"))
        refs = [Reference(exe, "kit:pads", env), Reference(exe, thru_port, env)]
        sent_ref, thru_ref = refs
        deadline = time.monotonic() + 20
        while not thru_ref.events and time.monotonic() < deadline:  # JACK connects lazily
            kit.send_message([0x99, 36, 1])
            time.sleep(0.2)
        assert thru_ref.events, (tmp_path / "input.err").read_text()[-800:]
        time.sleep(0.3)
        first = len(sent_ref.events), len(thru_ref.events)
        for k in range(30):
            kit.send_message([0x99, 22 if k % 2 else 38, 40 + k])  # hi-hat edge, snare
            time.sleep(0.03)
        time.sleep(0.5)
    finally:
        for ref in refs:
            ref.close()
        daemon.terminate()
        daemon.wait(15)
        kit.close_port()
    sent = sent_ref.events[first[0] :]
    got = thru_ref.events[first[1] :]
    assert [e[1] for e in got] == [(42 if k % 2 else 38, 40 + k) for k in range(30)]
    assert [e[1][1] for e in sent] == [40 + k for k in range(30)]
    lag_ms = (np.array([e[0] for e in got]) - np.array([e[0] for e in sent])) * 1000
    print(
        f"thru added latency: p50 {np.percentile(lag_ms, 50):.2f} ms, "
        f"p99 {np.percentile(lag_ms, 99):.2f} ms, max {lag_ms.max():.2f} ms"
    )
    assert np.all(lag_ms > 0) and np.percentile(lag_ms, 50) < 10.0
    err = (tmp_path / "input.err").read_text()
    assert "thru: " in err and " failed" in err and ", 0 failed" in err, err[-800:]


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_display_sends_a_files_notes_with_the_frames_that_show_them(
    jack_rig_server: str, tmp_path: Path
) -> None:
    from services.bench._jack import jack_env
    from services.bench.input_load import Reference, build_reference
    from tests.services.display.test_window_sound import HITS, hits_file, picture_times

    exe = build_reference(tmp_path)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(jack_env(jack_rig_server))
    midi, log = hits_file(tmp_path / "hits.mid"), tmp_path / "frames.jsonl"
    cmd = (
        f"{sys.executable} -m services display {midi} --map general-midi --size 320x180 "
        f"--aa 0 --seconds 5.5 --no-sound --midi-out ldsampler --frame-log {log}"
    )
    window = subprocess.Popen(
        ["xvfb-run", "-a", "-s", "-screen 0 320x180x24", "sh", "-c", cmd],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    ref = None
    try:
        deadline = time.monotonic() + 30
        port = None
        while port is None and time.monotonic() < deadline:  # the window opens its port
            ports = subprocess.run(["jack_lsp"], capture_output=True, text=True, env=env).stdout
            port = next((p for p in ports.splitlines() if p.endswith(":ldsampler")), None)
            time.sleep(0.05)
        assert port is not None, "the display opened no MIDI port"
        ref = Reference(exe, port, env)
        _, err = window.communicate(timeout=120)
    finally:
        if ref is not None:
            ref.close()
        if window.poll() is None:
            window.kill()
    assert window.returncode == 0, err[-1500:]
    assert "5 notes sent" in err, err[-1500:]
    assert ref is not None and [e[1][0] for e in ref.events] == [36, 38, 36, 38, 36]
    sent = np.array([e[0] for e in ref.events])
    seen, frame_s = picture_times(log, HITS)
    gap = sent - seen
    print(
        f"midi-out note - picture: {np.round(gap * 1000, 1).tolist()} ms, frames "
        f"{np.round(frame_s * 1000, 1).tolist()} ms"
    )
    # the contact is on screen from the frame around it; the note is timed for when a frame is
    # seen by the median draw time, so a frame far off the median (a loaded machine) moves the
    # picture, not the note: allowed one median frame more
    rows = [json.loads(line)["mono"] for line in log.read_text().splitlines()]
    median = float(np.median(np.diff(rows)))
    assert np.all(np.abs(gap) <= frame_s + median), (gap, frame_s, median)
