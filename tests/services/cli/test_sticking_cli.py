"""``livedrummer sticking``: JSON, the sheet, and a hand-edited text score read back."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from services.cli import main
from tests.livedrummer.sticking.test_sticking_helpers import DEMO


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["sticking", str(DEMO), "--map", "roland-td", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_json_lists_every_onset_in_time_order(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "--json")
    assert code == 0
    rows = json.loads(out)
    assert [r["time_s"] for r in rows] == sorted(r["time_s"] for r in rows)
    assert set(rows[0]) == {
        "time_s",
        "note",
        "piece",
        "limb",
        "reason",
        "too_fast",
        "crossed",
        "hard",
    }
    assert {r["limb"] for r in rows} <= {"RH", "LH", "RF", "LF"}
    assert all(r["reason"] is None or isinstance(r["reason"], str) for r in rows)
    # a note is hard exactly when it is too fast or crossed, and then it says why
    assert all((r["hard"] is not None) == (r["too_fast"] or r["crossed"]) for r in rows)
    assert any(r["too_fast"] for r in rows)  # the demo groove has a few fast flams


@pytest.mark.parametrize(
    "args", [("--sticking", "smed"), ("--strategy", "smed"), ("--lookahead-ms", "30")]
)
def test_other_strategies_and_online(
    capsys: pytest.CaptureFixture[str], args: tuple[str, ...]
) -> None:
    code, out, _ = run(capsys, *args, "--kit", "rock5-left")
    assert code == 0 and "bar 1" in out


def test_edited_text_score_is_honoured(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    _, text, _ = run(capsys, "--format", "text")
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if " hihat " in line and " RH" in line)
    lines[k] = lines[k].replace(" RH", " LH")
    edited = tmp_path / "edited.txt"
    edited.write_text("\n".join(lines) + "\n")
    _, out, _ = run(capsys, "--json", "--score", str(edited))
    rows = json.loads(out)
    time_s = float(lines[k].split()[0])
    row = next(r for r in rows if abs(r["time_s"] - time_s) < 1e-5 and r["piece"] == "hihat")
    assert row["limb"] == "LH"


def test_bad_options_are_one_line_errors(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, _, err = run(capsys, "--lookahead-ms", "30", "--sticking", "smed")
    assert code == 2 and "lookahead" in err
    missing = tmp_path / "none.txt"
    code, _, err = run(capsys, "--score", str(missing))
    assert code == 2 and "none.txt" in err


def test_sheet_marks_and_explains_notes_too_hard_to_play(
    capsys: pytest.CaptureFixture[str],
) -> None:
    _, out, _ = run(capsys, "--json")
    hard = [r for r in json.loads(out) if r["hard"]]
    _, sheet, _ = run(capsys)
    marked = [line for line in sheet.splitlines() if line.startswith("    ! ")]
    assert len(marked) == len(hard) > 0
    assert all(r["hard"] in line for r, line in zip(hard, marked, strict=True))
    assert sheet.count("!") >= 2 * len(hard)  # the mark in the row, and the line after the bar
    assert f"too hard to play (!): {len(hard)} of" in sheet.splitlines()[-1]
