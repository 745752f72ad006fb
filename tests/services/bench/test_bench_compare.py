"""``bench latency --compare``: the rows a run prints read back, the temporary worktree, the
options passed on."""

from __future__ import annotations

import contextlib
import io
import subprocess
from pathlib import Path

import numpy as np
import pytest

from livedrummer.errors import ConfigError
from services.bench import _compare, latency

REPO = Path(__file__).resolve().parents[3]


def _run(late: int, answered: str, rng: np.random.Generator) -> dict[str, object]:
    stage = {
        k: rng.uniform(0.001, 0.05, 40)
        for k in (
            "loopback",
            "bus",
            "pose",
            "frame",
            "frame_onset",
            "after_onset",
            "after_bus",
            "in_daemon",
        )
    }
    return {
        **stage,
        "sent": 300,
        "on_bus": 299,
        "no_contact": 2,
        "late": late,
        "late_where": "none late",
        "synth": f"synth: 299 onsets, answered in {answered} ms p50/p99, 0 contacts late",
    }


def test_the_rows_a_run_prints_are_read_back(capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(3)
    runs = {"100": _run(4, "0.8/1.9", rng), "groove": _run(0, "-/-", rng)}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for label, r in runs.items():
            latency._print_run(r, label)
    got = _compare.parse(out.getvalue())
    assert set(got) == {"100", "groove"}
    row = got["100"]
    assert row["late"] == 4 and row["no_pose"] == 2
    assert row["answer_p50"] == 0.8 and row["answer_p99"] == 1.9
    for key, stage in (("pose_bus", "after_bus"), ("frame", "frame"), ("bus", "bus")):
        a = runs["100"][stage]
        assert isinstance(a, np.ndarray)
        assert row[f"{key}_p99"] == pytest.approx(np.percentile(a, 99) * 1000, abs=0.006)
    assert "answer_p50" not in got["groove"], "a missing figure stays missing"
    _compare.print_side_by_side({"abc": [got, got], "this": [got, got]}, "abc")
    table = capsys.readouterr().out
    assert "x1.00" in table and "groove" in table


def test_the_options_are_passed_on_without_compare() -> None:
    argv = ["--rates", "100", "--compare", "abc", "--groove", "30", "--compare-runs=3"]
    assert latency._without_compare(argv) == ["--rates", "100", "--groove", "30"]
    argv = ["--compare", "abc", "def", "--compare-runs", "2", "--rates", "1", "100"]
    assert latency._without_compare(argv) == ["--rates", "1", "100"]
    assert latency._without_compare(["--groove", "30", "--compare=abc"]) == ["--groove", "30"]


@pytest.mark.parametrize("names", [["this", "a"], ["this", "a", "b"]])
def test_each_commit_goes_first_and_last_as_often(names: list[str]) -> None:
    turns = _compare.order(names, 2 * len(names))
    assert len(turns) == 2 * len(names) ** 2
    rounds = [turns[i : i + len(names)] for i in range(0, len(turns), len(names))]
    assert all(sorted(r) == sorted(names) for r in rounds)
    for pos in (0, -1):
        firsts = [r[pos] for r in rounds]
        assert all(firsts.count(n) == 2 for n in names)
    assert _compare.order(["this", "a"], 2) == ["this", "a", "a", "this"]


def test_the_other_commit_is_checked_out_beside_and_removed() -> None:
    head = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
    with _compare.worktree(REPO, head) as path:
        assert (path / "livedrummer").is_dir()
        assert _compare.bench_argv(path)[-2:] == ["bench", "latency"]
        kept = path
    assert not kept.exists()
    listed = subprocess.run(
        ["git", "-C", str(REPO), "worktree", "list"], capture_output=True, text=True, check=True
    ).stdout
    assert str(kept) not in listed
    with pytest.raises(ConfigError, match="--compare no-such-rev"):
        with _compare.worktree(REPO, "no-such-rev"):
            pass
