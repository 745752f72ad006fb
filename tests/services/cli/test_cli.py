"""The command line as a user meets it: real processes, exit codes, one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
FUNK = "drummer1/session1/1_funk_80_beat_4-4.mid"


SCRIPT = Path(sys.executable).parent / "livedrummer"  # the installed console script


def run(*args: str, **env: str) -> subprocess.CompletedProcess[str]:
    command = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "services"]
    return subprocess.run(
        [*command, *args], capture_output=True, text=True, timeout=120, env={**os.environ, **env}
    )


def test_inspect_json_on_a_groove(groove_dir: Path) -> None:
    proc = run("inspect", str(groove_dir / FUNK), "--map", "roland-td", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["onsets"] == sum(int(v) for v in out["by_note"].values())
    assert out["unknown_notes"] == {}
    assert out["duration_s"] == pytest.approx(87.0, abs=0.1)
    assert out["by_note"]["36"] == out["by_piece"]["kick"]["head"]
    assert out["tempos_bpm"] == [[0.0, 80.0]] and out["meters"] == [[0.0, 4, 4]]


def test_inspect_text_reports_unknown_notes_with_the_wrong_map(groove_dir: Path) -> None:
    proc = run("inspect", str(groove_dir / FUNK), "--map", "general-midi")
    assert proc.returncode == 0, proc.stderr
    assert "UNKNOWN   note 26 x8 (not in map general-midi" in proc.stdout


@pytest.mark.parametrize("content", [b"", os.urandom(2000), b"MThd\x00\x00\x00\x06\x00"])
def test_bad_files_exit_2_with_one_line(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "bad.mid"
    path.write_bytes(content)
    proc = run("inspect", str(path), "--map", "roland-td")
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"livedrummer: error: {path}: ")
    assert "Traceback" not in proc.stderr


def test_directory_and_bad_map_exit_2(tmp_path: Path) -> None:
    proc = run("inspect", str(tmp_path))
    assert proc.returncode == 2 and "is a directory" in proc.stderr
    proc = run("inspect", str(tmp_path), "--map", "nope")
    assert proc.returncode == 2 and "unknown note map 'nope'" in proc.stderr


def test_bad_bench_lists_exit_2_naming_the_option() -> None:
    """A mistyped ``--hogs`` or ``--modes`` list, before any server or hog starts."""
    for args, line in [
        (("--hogs", "1,two"), "argument --hogs: expected counts like 0,1x,2x"),
        (("--hogs", "-1"), "argument --hogs: expected counts"),
        (("--modes", "sync,asink"), "argument --modes: 'asink': expected"),
    ]:
        proc = run("bench", "input_load", *args)
        assert proc.returncode == 2 and line in proc.stderr, proc.stderr
        assert "Traceback" not in proc.stderr
    proc = run("bench", "recovery", "--hogs", "x")
    assert proc.returncode == 2 and "argument --hogs" in proc.stderr


def test_kit_typo_exit_2(tmp_path: Path) -> None:
    kit = tmp_path / "kits"
    kit.mkdir()
    text = (REPO / "kits" / "rock5.toml").read_text().replace("tilt_deg", "tilt_dge", 1)
    (kit / "rock5.toml").write_text(text)
    proc = run("kits", LIVEDRUMMER_PATH=str(tmp_path))
    assert proc.returncode == 0
    assert "tilt_dge: unknown key; did you mean 'tilt_deg'" in proc.stdout


def test_kits_lists_kits_and_maps() -> None:
    proc = run("kits")
    assert proc.returncode == 0, proc.stderr
    for name in ("rock5", "rock5-left", "general-midi", "roland-td", "yamaha-dtx", "alesis-nitro"):
        assert f"  {name} " in proc.stdout


def test_demo_plays_the_groove_live_and_records_it_without_a_screen(tmp_path: Path) -> None:
    out = tmp_path / "demo.mp4"
    proc = run(
        "demo",
        "--seconds",
        "4",
        "-o",
        str(out),
        DISPLAY="",
        WAYLAND_DISPLAY="",
        LIVEDRUMMER_HOME=str(tmp_path / "home"),
    )
    assert proc.returncode == 0, proc.stderr
    assert "gmd-drummer1-funk-80.mid" in proc.stdout and "played live" in proc.stdout
    assert f"up: wrote {out.resolve()}" in proc.stdout
    assert "up: stopped (0 restarts)" in proc.stderr
    assert out.stat().st_size > 10_000


def test_demo_offline_renders_the_bundled_groove(tmp_path: Path) -> None:
    out = tmp_path / "demo.mp4"
    proc = run(
        "demo", "--offline", "--seconds", "3", "-o", str(out), DISPLAY="", WAYLAND_DISPLAY=""
    )
    assert proc.returncode == 0, proc.stderr
    assert "gmd-drummer1-funk-80.mid" in proc.stdout
    assert "sticking  optimal:" in proc.stdout
    assert str(out) in proc.stdout
    assert out.stat().st_size > 10_000


def test_demo_takes_size_camera_and_kit(tmp_path: Path) -> None:
    import av

    out = tmp_path / "demo.mp4"
    proc = run(
        "demo",
        "--offline",
        "--seconds",
        "1",
        "-o",
        str(out),
        "--size",
        "320x180",
        "--camera",
        "drummer",
        "--kit",
        "rock5-left",
        DISPLAY="",
        WAYLAND_DISPLAY="",
    )
    assert proc.returncode == 0, proc.stderr
    assert "320x180 @ 30 fps, camera drummer, kit rock5-left" in proc.stdout
    with av.open(str(out)) as c:
        v = c.streams.video[0].codec_context
        assert (v.width, v.height) == (320, 180)
    bad = run("demo", "--offline", "--camera", "nope", DISPLAY="", WAYLAND_DISPLAY="")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--camera 'nope'" in bad.stderr
    bad = run("demo", "--offline", "--map", "nope", DISPLAY="", WAYLAND_DISPLAY="")
    assert bad.returncode == 2 and "unknown note map 'nope'" in bad.stderr


def test_inspect_summarises_hundreds_of_tempo_changes(tmp_path: Path) -> None:
    import mido

    track = mido.MidiTrack()
    bpms = [60.0 + (i * 7) % 61 for i in range(300)]  # a rubato: 60-120 bpm, 300 changes
    for bpm in bpms:
        track.append(mido.MetaMessage("set_tempo", tempo=mido.bpm2tempo(bpm), time=0))
        track.append(mido.Message("note_on", channel=9, note=36, velocity=90, time=0))
        track.append(mido.Message("note_on", channel=9, note=36, velocity=0, time=240))
    mid = mido.MidiFile(ticks_per_beat=480)
    mid.tracks.append(track)
    path = tmp_path / "rubato.mid"
    mid.save(path)
    text = run("inspect", str(path), "--map", "general-midi")
    assert text.returncode == 0, text.stderr
    (line,) = [ln for ln in text.stdout.splitlines() if ln.startswith("  tempo")]
    assert line == "  tempo     300 tempos, 60-120 bpm (first 60 bpm at 0.00 s; --json lists them)"
    out = json.loads(run("inspect", str(path), "--map", "general-midi", "--json").stdout)
    assert [bpm for _, bpm in out["tempos_bpm"]] == pytest.approx(bpms, abs=1e-3)
