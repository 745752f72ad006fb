"""``livedrummer practice score`` on a take with planted mistakes, as a user runs it; bad input;
the practice database and ``practice history``."""

from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from services.practice.take import write_take
from tests.practice_takes import plant_take

SCRIPT = Path(sys.executable).parent / "livedrummer"
SOUL = "drummer1/eval_session/3_soul-groove3_86_beat_4-4.mid"


def run(*args: str, **env: str) -> subprocess.CompletedProcess[str]:
    command = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "services"]
    return subprocess.run(
        [*command, *args], capture_output=True, text=True, timeout=120, env={**os.environ, **env}
    )


def test_planted_take_scores_exactly(groove_dir: Path, tmp_path: Path) -> None:
    ref = groove_dir / SOUL
    take = tmp_path / "take.mid"
    planted = plant_take(ref, take, seed=11)
    home = tmp_path / "home"
    proc = run(
        "practice",
        "score",
        str(ref),
        str(take),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--json",
        "--save",
        LIVEDRUMMER_HOME=str(home),
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["reference_notes"] == planted.reference_notes
    assert (out["hits"], out["missed"], out["wrong_piece"], out["extra"]) == (
        planted.hits,
        planted.missed,
        planted.wrong_piece,
        planted.extra,
    )
    assert out["mean_offset_ms"] == pytest.approx(planted.mean_offset_ms, abs=0.5)
    assert len(out["notes"]) == planted.reference_notes
    assert {n["result"] for n in out["notes"]} == {"hit", "missed", "wrong_piece"}
    assert sum(p["hits"] for p in out["per_piece"].values()) == planted.hits
    assert sum(p["extra"] for p in out["per_piece"].values()) == planted.extra
    first = out["notes"][0]
    assert set(first) >= {"time_s", "piece", "result", "offset_ms"}
    # --save kept it under LIVEDRUMMER_HOME; history lists it.
    rows = sqlite3.connect(home / "practice.sqlite").execute("SELECT hits FROM session").fetchall()
    assert rows == [(planted.hits,)]
    hist = run("practice", "history", "--json", LIVEDRUMMER_HOME=str(home))
    assert hist.returncode == 0, hist.stderr
    assert json.loads(hist.stdout)["sessions"][0]["hits"] == planted.hits


def test_text_output_and_pieces(groove_dir: Path, tmp_path: Path) -> None:
    ref = groove_dir / SOUL
    take = tmp_path / "take.mid"
    plant_take(ref, take, seed=4, deleted=0, moved=0, extra=0)
    proc = run(
        "practice",
        "score",
        str(ref),
        str(take),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--pieces",
        "snare",
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert " 0 missed, 0 extra" in lines[0]
    assert [ln.split()[0] for ln in lines[3:]] == ["snare"]


def test_align_first_judges_an_export_that_starts_at_its_first_hit(
    groove_dir: Path, tmp_path: Path
) -> None:
    ref = groove_dir / SOUL
    take = tmp_path / "take.mid"
    planted = plant_take(ref, take, seed=3, deleted=2, moved=0, extra=0, sd_ms=0.0, mean_ms=0.0)
    export = tmp_path / "export.mid"
    notes = read_midi_file(take, load_note_map("roland-td")).onsets
    notes["time_s"] -= float(notes["time_s"][0]) - 1.0  # + the take's 1 s lead: starts at 0
    write_take(export, notes, lead_s=0.0)
    plain = run(
        "practice",
        "score",
        str(ref),
        str(export),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--json",
    )
    aligned = run(
        "practice",
        "score",
        str(ref),
        str(export),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--json",
        "--align",
        "first",
    )
    assert json.loads(aligned.stdout)["hits"] == planted.hits
    assert json.loads(aligned.stdout)["mean_offset_ms"] == pytest.approx(0.0, abs=0.5)
    assert json.loads(plain.stdout)["hits"] < planted.hits


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--window-ms", "0"], "--window-ms 0: expected > 0"),
        (["--pieces", "snare,bongo"], "--pieces: unknown piece 'bongo'"),
    ],
)
def test_bad_options_one_line(groove_dir: Path, args: list[str], message: str) -> None:
    ref = str(groove_dir / SOUL)
    proc = run("practice", "score", ref, ref, *args)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines()[-1].startswith("livedrummer: error: ")
    assert message in proc.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--bars", "9:999"], "--bars: 9:999: the reference has"),
        (["--bars", "3"], "--bars: '3': expected BAR:BAR"),
        (["--quiet-count", "0:1"], "--quiet-count 0:1: expected ON:OFF"),
        (["--tempo", "9"], "--tempo 9: expected 0.1..4"),
    ],
)
def test_live_bad_options_one_line_before_any_device(
    groove_dir: Path, args: list[str], message: str
) -> None:
    proc = run("practice", str(groove_dir / SOUL), "--serial", "/nonexistent/tty", *args)
    assert proc.returncode == 2
    assert message in proc.stderr.strip().splitlines()[-1], proc.stderr


def test_truncated_take_one_line_exit_2(groove_dir: Path, tmp_path: Path) -> None:
    ref = groove_dir / SOUL
    bad = tmp_path / "cut.mid"
    bad.write_bytes(ref.read_bytes()[:200])
    proc = run("practice", "score", str(ref), str(bad), "--map", "roland-td")
    assert proc.returncode == 2
    errors = [ln for ln in proc.stderr.splitlines() if "error" in ln]
    assert len(errors) == 1 and str(bad) in errors[0], proc.stderr
    assert "Traceback" not in proc.stderr


def test_newer_database_is_one_line(tmp_path: Path) -> None:
    db = tmp_path / "p.sqlite"
    sqlite3.connect(db).execute("PRAGMA user_version = 99").connection.close()
    proc = run("practice", "history", "--db", str(db))
    assert proc.returncode == 2
    assert f"{db}: practice database version 99 is newer" in proc.stderr


def test_json_and_text_name_the_windows_and_grades_alike(groove_dir: Path, tmp_path: Path) -> None:
    ref = groove_dir / SOUL
    take = tmp_path / "take.mid"
    plant_take(ref, take, seed=5)
    args = (
        "practice",
        "score",
        str(ref),
        str(take),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--window-ms",
        "80",
        "--level",
        "hard",
    )
    proc, text = run(*args, "--json"), run(*args)
    assert proc.returncode == 0 and text.returncode == 0, proc.stderr + text.stderr
    out = json.loads(proc.stdout)
    assert "window_ms" not in out and "level_window_ms" not in out  # the words of the past
    assert (out["match_window_ms"], out["on_time_window_ms"], out["level"]) == (80.0, 20.0, "hard")
    assert out["grade_limits_ms"] == {"perfect": 20.0, "good": 40.0, "ok": 80.0}
    lines = text.stdout.splitlines()
    assert f"{out['hits']} hits (match window ±80 ms)" in lines[0]
    assert (
        f"perfect {out['perfect']} (≤ 20 ms), good {out['good']} (≤ 40 ms), "
        f"ok {out['ok']} (≤ 80 ms)"
    ) in lines[1]
    assert lines[2].startswith(f"accuracy {out['accuracy_pct']:.1f} % (on time ±20 ms, hard)")
    assert "100 ms" not in text.stdout  # the default window appears nowhere


def test_a_file_scored_against_itself_says_its_notices_once(
    groove_dir: Path, tmp_path: Path
) -> None:
    ref = groove_dir / SOUL
    proc = run("practice", "score", str(ref), str(ref))  # both read with --map auto
    assert proc.returncode == 0, proc.stderr
    said = [line for line in proc.stderr.splitlines() if "map auto:" in line]
    assert len(said) == 1 and said[0].startswith(f"livedrummer: {ref}: "), proc.stderr
    take = tmp_path / "take.mid"
    plant_take(ref, take, seed=3)
    other = run("practice", "score", str(ref), str(take))  # a take of its own is named apart
    assert other.returncode == 0, other.stderr
    named = {line.split(": ")[1] for line in other.stderr.splitlines() if "map auto:" in line}
    assert named == {str(ref), str(take)}, other.stderr
