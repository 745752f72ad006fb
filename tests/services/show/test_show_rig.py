"""The first ten minutes on a real JACK server: a virtual port, the monitor, failing loudly.

Everything runs as a user would run it (``python -m services ...`` subprocesses) against a
real ``jackd -d dummy`` (no sound card): a virtual input port that a keyboard or a DAW plays
into, ``monitor`` printing what arrives and what it means, a port that is not there refused
in one line naming what is (exit 2, no journal written), and ``--wait`` waiting visibly and
creating the session's journal only once the port has opened.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zmq

from livedrummer import protocol as p

rtmidi = pytest.importorskip("rtmidi")


def cli(*args: str, env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "services", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def wait_port(name: str, timeout_s: float = 20.0) -> str:
    """The full name of a JACK MIDI *input* port ending in ``name`` (an output's destination)."""
    probe = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "probe")
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            hits = [q for q in probe.get_ports() if q.endswith(f":{name}")]
            if hits:
                return str(hits[0])
            time.sleep(0.05)
        raise AssertionError(
            f"no JACK input port {name!r} within {timeout_s} s: {probe.get_ports()}"
        )
    finally:
        probe.delete()


def player(port: str) -> Any:
    """A MIDI output of the test, connected to ``port`` (a virtual input of ours)."""
    out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "player")
    names = out.get_ports()
    out.open_port(names.index(port))
    time.sleep(0.2)  # the connection reaches the JACK graph within a cycle or two
    return out


@pytest.fixture
def home(tmp_path: Path) -> Iterator[dict[str, str]]:
    yield {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}


def test_a_virtual_port_feeds_the_input_daemon(
    jack_server: str, tmp_path: Path, home: dict[str, str]
) -> None:
    proc = cli(
        "input",
        "--virtual",
        "pads",
        "--api",
        "jack",
        "--map",
        "roland-td",
        "--pub",
        "tcp://127.0.0.1:*",
        "--control",
        "tcp://127.0.0.1:*",
        "--sessions-dir",
        str(tmp_path / "sessions"),
        env=home,
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    sub = ctx.socket(zmq.SUB)
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
        sub.connect(info["pub"])
        out = player(wait_port("pads"))
        notes = [(38, 100), (48, 80), (36, 120), (42, 64)]
        seen: list[tuple[int, int]] = []
        deadline = time.monotonic() + 10
        sent = False
        while len(seen) < len(notes) and time.monotonic() < deadline:
            if not sent:
                for note, velocity in notes:
                    out.send_message([0x99, note, velocity])
                    time.sleep(0.01)
                sent = True
            if sub.poll(200):
                msg = p.decode(sub.recv_multipart())
                seen += [(int(r["note"]), int(r["velocity"])) for r in msg.body]
        out.close_port()
        assert seen == notes
        assert Path(info["journal"]).exists()  # the port opened at once: the journal is there
    finally:
        sub.close(0)
        ctx.term()
        proc.terminate()
        proc.communicate(timeout=20)


def test_monitor_prints_each_message_and_its_meaning(
    jack_server: str, home: dict[str, str]
) -> None:
    proc = cli(
        "monitor",
        "--virtual",
        "watch",
        "--api",
        "jack",
        "--map",
        "roland-td",
        "--json",
        "--seconds",
        "6",
        env=home,
    )
    out = player(wait_port("watch"))
    for message in ([0x99, 38, 100], [0x99, 99, 50], [0xB9, 4, 90], [0xA9, 49, 127], [0x89, 38, 0]):
        out.send_message(message)
        time.sleep(0.02)
    out.close_port()
    stdout, stderr = proc.communicate(timeout=30)
    assert proc.returncode == 0, stderr
    lines = [json.loads(line) for line in stdout.splitlines()]
    assert [(r["type"], r["number"], r["value"]) for r in lines] == [
        ("note_on", 38, 100),
        ("note_on", 99, 50),
        ("control_change", 4, 90),
        ("polytouch", 49, 127),
        ("note_off", 38, 0),
    ]
    assert all(r["channel"] == 10 for r in lines)
    assert "snare" in lines[0]["meaning"].lower() and lines[0]["known"]
    assert lines[1]["meaning"].startswith("unknown note") and not lines[1]["known"]
    assert "hi-hat pedal" in lines[2]["meaning"]
    assert lines[3]["meaning"].startswith("choke")
    assert lines == sorted(lines, key=lambda r: r["time_s"])
    assert "5 messages, 1 unknown" in stderr


def test_a_missing_port_is_one_line_naming_what_exists_and_leaves_no_journal(
    jack_server: str, tmp_path: Path, home: dict[str, str]
) -> None:
    kit = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
    kit.open_virtual_port("pads")
    try:
        run = subprocess.run(
            [
                sys.executable,
                "-m",
                "services",
                "input",
                "--midi",
                "TD-17",
                "--api",
                "jack",
                "--map",
                "roland-td",
                "--sessions-dir",
                str(tmp_path / "sessions"),
            ],
            capture_output=True,
            text=True,
            timeout=60,
            env=home,
        )
    finally:
        kit.close_port()
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1, run.stderr
    assert "'TD-17': not found" in lines[0] and "kit:pads" in lines[0] and "--wait" in lines[0]
    assert not list((tmp_path / "sessions").glob("*"))


def test_wait_says_it_is_waiting_and_journals_only_once_the_port_opens(
    jack_server: str, tmp_path: Path, home: dict[str, str]
) -> None:
    sessions = tmp_path / "sessions"
    proc = cli(
        "input",
        "--midi",
        "late",
        "--wait",
        "--api",
        "jack",
        "--map",
        "roland-td",
        "--pub",
        "tcp://127.0.0.1:*",
        "--control",
        "tcp://127.0.0.1:*",
        "--sessions-dir",
        str(sessions),
        env=home,
    )
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        time.sleep(6.5)  # one status line every 5 s while the port is absent
        assert not Path(info["journal"]).exists()
        kit = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
        kit.open_virtual_port("late")
        deadline = time.monotonic() + 10
        while not Path(info["journal"]).exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert Path(info["journal"]).exists()
        kit.close_port()
    finally:
        proc.terminate()
        _, stderr = proc.communicate(timeout=20)
    assert "source unavailable" in stderr and "still waiting (5 s)" in stderr
    assert "connected after" in stderr
    assert len(list(sessions.glob("*"))) == 1


@pytest.mark.parametrize(
    ("args", "expect"),
    [
        (["--demo", "--fps", "0"], "--fps: expected 0 < fps <= 1000 (got 0)"),
        (["--demo", "--size", "abc"], "--size 'abc'"),
        (["--demo", "--delay-ms", "-5"], "--lookahead-ms 30 must be between 0 and --delay-ms -5"),
        (["--serial", "/dev/ttyNOPE9"], "serial:/dev/ttyNOPE9: no such device"),
    ],
)
def test_up_checks_every_option_before_starting_anything(
    args: list[str], expect: str, home: dict[str, str]
) -> None:
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            *args,
            "--headless",
            "--seconds",
            "1",
            "--map",
            "roland-td",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("livedrummer: error: "), run.stderr
    assert expect in run.stderr
    assert "running" not in run.stdout  # no service was started


def test_render_checks_aa_and_writes_the_target_only_when_whole(
    tmp_path: Path, home: dict[str, str]
) -> None:
    groove = Path(__file__).resolve().parents[3] / "kits" / "grooves"
    song = next(groove.glob("*.mid"))
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            str(song),
            "--aa",
            "3",
            "-o",
            str(tmp_path / "x.mp4"),
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert bad.returncode == 2 and bad.stderr.strip().splitlines()[-1].startswith(
        "livedrummer: error: --aa 3: expected one of"
    )
    out = tmp_path / "song.mp4"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            str(song),
            "-o",
            str(out),
            "--size",
            "160x90",
            "--fps",
            "10",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=home,
    )
    part = tmp_path / "song.part.mp4"
    deadline = time.monotonic() + 60
    while not part.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert part.exists() and not out.exists()  # while rendering, only the part file
    proc.communicate(timeout=300)
    assert proc.returncode == 0
    assert out.exists() and not part.exists()


def test_a_late_avatar_is_reported_live_and_in_the_summary(
    tmp_path: Path, home: dict[str, str]
) -> None:
    # D = 1 ms: no synth answers a hit within a millisecond, so every contact is late.
    base = 20_000 + (os.getpid() % 1000) * 20
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--headless",
            "--seconds",
            "4",
            "--delay-ms",
            "1",
            "--lookahead-ms",
            "0",
            "--port-base",
            str(base),
            "--frames-dir",
            str(tmp_path / "f"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=home,
    )
    out = run.stdout + run.stderr
    assert run.returncode == 0, out[-2000:]
    assert "synth: " in out and "contacts published after their show time (the first" in out
    late = int(out.split(" contacts late")[0].rsplit(", ", 1)[1])
    assert late > 0
    # the lines say what was measured and what it means; the knob is named, not ordered
    lines = [
        ln
        for ln in out.splitlines()
        if "after their show time" in ln or "after every frame they cover" in ln
    ]
    assert lines and all("measured on this machine" in ln and "raise" not in ln for ln in lines)
    # no --png: the folder holds the frame log only, and up says so
    log = tmp_path / "f" / "frames.jsonl"
    assert log.exists() and not list((tmp_path / "f").glob("*.png"))
    assert f"up: input, synth and display running; frame log in {log}" in run.stdout
    assert f"restarts); frame log in {log}" in run.stderr  # up: stopped (N restarts); ...
    assert f"frame log in {log}, " in run.stderr and "frames into" not in run.stderr  # display


def write_rig(path: Path, port_base: int) -> Path:
    path.write_text(
        "[source]\ndemo = true\n"
        '[show]\nkit = "rock5"\ncamera = "front"\nfps = 20\nsize = "160x90"\nheadless = true\n'
        f"[network]\nport_base = {port_base}\n"
    )
    return path


def test_up_runs_the_rig_profile_and_refuses_a_bad_one(
    tmp_path: Path, home: dict[str, str]
) -> None:
    base = 30_000 + (os.getpid() % 1000) * 20
    rig = write_rig(tmp_path / "rig.toml", base)
    frames = tmp_path / "frames"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--rig",
            str(rig),
            "--seconds",
            "3",
            "--frames-dir",
            str(frames),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=home,
    )
    assert run.returncode == 0, (run.stdout + run.stderr)[-2000:]
    assert f"tcp://127.0.0.1:{base}" in run.stdout  # the profile's port base was used
    records = [json.loads(line) for line in (frames / "frames.jsonl").read_text().splitlines()]
    assert records and any(r["pose_s"] for r in records)
    (tmp_path / "bad.toml").write_text('[show]\ncamra = "front"\n')
    bad = subprocess.run(
        [sys.executable, "-m", "services", "up", "--rig", str(tmp_path / "bad.toml")],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert bad.returncode == 2
    lines = bad.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].endswith("bad.toml: [show] camra: unknown key"), lines
    none = subprocess.run(
        [sys.executable, "-m", "services", "up"],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert none.returncode == 2 and "give --midi PORT, --serial DEV or --demo" in none.stderr


def test_deploy_writes_a_unit_systemd_accepts(tmp_path: Path, home: dict[str, str]) -> None:
    rig = write_rig(tmp_path / "rig.toml", 5710)
    units = tmp_path / "units"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "deploy",
            "systemd",
            "--unit-dir",
            str(units),
            "--rig",
            str(rig),
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert run.returncode == 0, run.stderr
    unit = (units / "livedrummer-rig.service").read_text()
    assert f"ExecStart={sys.executable} -m services up --rig {rig.resolve()} --wait" in unit
    assert "RestartPreventExitStatus=2" in unit and "Restart=on-failure" in unit
    assert "systemctl --user enable --now livedrummer-rig.service" in run.stdout
    assert "loginctl enable-linger" in run.stdout
    analyze = shutil.which("systemd-analyze")
    if analyze is not None:
        verify = subprocess.run(
            [analyze, "verify", str(units / "livedrummer-rig.service")],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert verify.returncode == 0, verify.stderr


def test_map_learn_writes_a_map_from_hits_that_the_file_commands_load(
    jack_server: str, tmp_path: Path, home: dict[str, str]
) -> None:
    out = tmp_path / "mymodule.toml"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "map",
            "learn",
            "--virtual",
            "learnpads",
            "--api",
            "jack",
            "-o",
            str(out),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=home,
    )
    assert proc.stdin is not None and proc.stdout is not None
    kit = player(wait_port("learnpads"))
    # What this (imaginary) module sends for each prompt; None = the drummer skips it.
    answers: dict[str, list[list[int]] | None] = {
        "Kick": [[0x99, 35, 100]],
        "Snare head": [[0x99, 37, 90]],
        "Snare rim (rim shot)": [[0x99, 37, 80], [0x99, 39, 110]],  # 37 is taken: refused
        "Snare cross stick": None,
        "Hi-hat closed (bow)": [[0x99, 41, 70]],
        "Hi-hat closed (edge)": None,
        "Hi-hat open (bow)": [[0x99, 43, 70]],
        "Hi-hat open (edge)": None,
        "Hi-hat pedal (close it, open it, close it)": [
            [0xB9, 4, 120],
            [0xB9, 4, 0],
            [0xB9, 4, 120],
            [0x99, 44, 60],
        ],
        "Tom 1": [[0x99, 48, 100]],
        "Tom 1 rim": None,
        "Tom 2": [[0x99, 45, 100]],
    }
    seen: list[str] = []
    try:
        while True:
            line = proc.stdout.readline()
            if not line.startswith("hit: "):
                seen.append(line.strip())
                if not line or line.startswith("wrote"):
                    break
                continue
            label = line[len("hit: ") :].split("   (")[0]
            seen.append(label)
            if label not in answers:
                proc.stdin.write("q\n")
                proc.stdin.flush()
                continue
            messages = answers[label]
            if messages is None:
                proc.stdin.write("\n")
                proc.stdin.flush()
            else:
                for m in messages:
                    kit.send_message(m)
                    time.sleep(0.05)
        proc.wait(timeout=30)
    finally:
        kit.close_port()
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, proc.stderr.read() if proc.stderr else ""
    assert any("note 37 is already Snare head" in s for s in seen)
    from livedrummer.midi.notemap import load_note_map

    learned = load_note_map(str(out))
    assert {n: (s.instrument, s.zone.value) for n, s in learned.notes.items()} == {
        35: ("kick", "head"),
        37: ("snare", "head"),
        39: ("snare", "rim"),
        41: ("hihat", "bow"),
        43: ("hihat", "bow"),
        44: ("hihat", "pedal"),
        48: ("tom1", "head"),
        45: ("tom2", "head"),
    }
    assert learned.hihat_cc == 4 and learned.hihat_cc_closed == 120
    assert learned.notes[43].hihat.value == "open" and learned.notes[41].hihat.value == "closed"
    # The file commands play a file recorded on this module with the learned map.
    import mido

    song = tmp_path / "played.mid"
    mid = mido.MidiFile()
    track = mido.MidiTrack()
    mid.tracks.append(track)
    for note in (35, 37, 39, 48, 45):
        track.append(mido.Message("note_on", channel=9, note=note, velocity=100, time=120))
    mid.save(song)
    shown = subprocess.run(
        [sys.executable, "-m", "services", "inspect", str(song), "--map", str(out), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
        env=home,
    )
    assert shown.returncode == 0, shown.stderr
    summary = json.loads(shown.stdout)
    assert summary["onsets"] == 5 and summary["unknown_notes"] == {}
    assert summary["by_piece"] == {
        "kick": {"head": 1},
        "snare": {"head": 1, "rim": 1},
        "tom1": {"head": 1},
        "tom2": {"head": 1},
    }


def test_calibrate_recovers_a_players_offset_through_a_real_pty(
    tmp_path: Path, home: dict[str, str]
) -> None:
    """A scripted player hits 23 ms after each click, through a real pseudo-terminal."""
    master, slave = os.openpty()
    tty = os.ttyname(slave)
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "calibrate",
            "--serial",
            tty,
            "--no-sound",
            "--json",
            "--clicks",
            "12",
            "--bpm",
            "240",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=home,
    )
    try:
        assert proc.stdout is not None
        clicks = json.loads(proc.stdout.readline())["clicks_s"]
        for i, click in enumerate(clicks):
            if i == 5:
                continue  # a missed click
            while time.monotonic() < click + 0.023:
                time.sleep(0.0002)
            os.write(master, bytes([0x99, 38, 100]))
        os.write(master, bytes([0x99, 38, 90]))  # a stray hit after the last click
        out, err = proc.communicate(timeout=60)
    finally:
        os.close(master)
        os.close(slave)
    assert proc.returncode == 0, err
    result = json.loads(out.strip().splitlines()[-1])
    assert abs(result["lag_ms"] - 23.0) < 1.0, result
    assert result["hits_used"] == 11 and result["hits_dropped"] == 1
    written = Path(home["LIVEDRUMMER_HOME"]) / "calibration.toml"
    assert result["written"] == str(written)
    from livedrummer.live.calibration import Calibration

    assert abs(Calibration.load(written).input_ms + result["lag_ms"]) < 0.01
