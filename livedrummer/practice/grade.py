"""Grades and scores of a judged take (:mod:`livedrummer.practice.match`): the numbers a player
sees, the same in the terminal, ``practice score --json`` and the reports.

**Timing grades.** A hit (same piece, within the matching window) gets a grade by |offset|:

============  ===========  =====================================================
grade         |offset|     meaning
============  ===========  =====================================================
``perfect``   ≤ 20 ms      inside the HARD window (Roland Coach's strict setting)
``good``      ≤ 40 ms      inside the EASY window
``ok``        ≤ window     matched but loose (early or late shown by the sign)
============  ===========  =====================================================

A wrong piece or a missed note has no timing grade. **Accuracy** (percent) is the share of
judged events that were hits inside the chosen window (EASY ±40 ms by default, HARD ±20 ms with
``level="hard"``): ``on_time / (reference notes + extra notes)``, so extra notes cost as much as
missed ones. **Score** (0 to 100) weighs every reference note: perfect 1, good 0.7, ok 0.4, wrong
piece 0.1, missed 0, divided by (reference notes + extra notes). Both are simple on purpose, so
a player can check them by hand; the windows are constants, not tuned per player.

**One vocabulary.** Two windows are at work and every output names them the same way: the
*match window* (``match_window_ms``, ``--window-ms``, default ±100 ms) decides whether a hit is
matched to a note at all, the *on-time window* (``on_time_window_ms``: ±40 ms easy, ±20 ms hard)
decides whether it counts for accuracy. ``grade_limits_ms`` gives each grade's bound
(perfect ≤ 20, good ≤ 40, ok ≤ the match window). ``practice score`` prints them beside the
counts they bound (:func:`window_words`), its ``--json`` gives these keys.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from livedrummer.practice.match import PIECES, RESULT_NAMES, Matching, Result

HARD_WINDOW_MS = 20.0
EASY_WINDOW_MS = 40.0


class Level(StrEnum):
    """Which window counts as on time for accuracy (Roland Coach's EASY and HARD)."""

    EASY = "easy"
    HARD = "hard"

    @property
    def window_ms(self) -> float:
        return EASY_WINDOW_MS if self is Level.EASY else HARD_WINDOW_MS


GRADE_POINTS: dict[str, float] = {"perfect": 1.0, "good": 0.7, "ok": 0.4, "wrong_piece": 0.1}


def grade_of(offset_ms: float) -> str:
    """``perfect``, ``good`` or ``ok`` for a hit's offset (see the module docstring)."""
    size = abs(offset_ms)
    if size <= HARD_WINDOW_MS:
        return "perfect"
    if size <= EASY_WINDOW_MS:
        return "good"
    return "ok"


def note_grades(notes: np.ndarray) -> list[str]:
    """Per reference note: its timing grade when a hit, else ``wrong_piece`` or ``missed``."""
    out = []
    for result, off in zip(notes["result"].tolist(), notes["offset_ms"].tolist(), strict=True):
        out.append(grade_of(off) if result == Result.HIT else RESULT_NAMES[result])
    return out


@dataclass(frozen=True)
class Tally:
    """Counts and timing statistics of a set of reference notes (a take, a piece, a pass)."""

    notes: int
    hits: int
    wrong_piece: int
    missed: int
    extra: int
    on_time: int  # hits inside the level's window
    perfect: int
    good: int
    ok: int
    mean_offset_ms: float | None
    sd_offset_ms: float | None
    median_offset_ms: float | None
    mean_velocity_diff: float | None

    @property
    def accuracy_pct(self) -> float:
        judged = self.notes + self.extra
        return 100.0 * self.on_time / judged if judged else 0.0

    @property
    def score(self) -> float:
        judged = self.notes + self.extra
        if not judged:
            return 0.0
        points = (
            GRADE_POINTS["perfect"] * self.perfect
            + GRADE_POINTS["good"] * self.good
            + GRADE_POINTS["ok"] * self.ok
            + GRADE_POINTS["wrong_piece"] * self.wrong_piece
        )
        return 100.0 * points / judged

    def as_json(self) -> dict[str, Any]:
        return {
            "reference_notes": self.notes,
            "hits": self.hits,
            "missed": self.missed,
            "extra": self.extra,
            "wrong_piece": self.wrong_piece,
            "perfect": self.perfect,
            "good": self.good,
            "ok": self.ok,
            "on_time": self.on_time,
            "accuracy_pct": round(self.accuracy_pct, 3),
            "score": round(self.score, 3),
            "mean_offset_ms": _round(self.mean_offset_ms),
            "sd_offset_ms": _round(self.sd_offset_ms),
            "median_offset_ms": _round(self.median_offset_ms),
            "mean_velocity_diff": _round(self.mean_velocity_diff),
        }


def _round(x: float | None) -> float | None:
    return None if x is None else round(x, 3)


def tally(notes: np.ndarray, extra: int, level: Level = Level.EASY) -> Tally:
    """The :class:`Tally` of ``notes`` (NOTE_DTYPE rows) plus ``extra`` extra notes."""
    result = notes["result"]
    hit = result == Result.HIT
    off = notes["offset_ms"][hit]
    size = np.abs(off)
    vel = notes["velocity_diff"][hit].astype(np.float64)
    return Tally(
        notes=int(notes.size),
        hits=int(hit.sum()),
        wrong_piece=int(np.count_nonzero(result == Result.WRONG_PIECE)),
        missed=int(np.count_nonzero(result == Result.MISSED)),
        extra=int(extra),
        on_time=int(np.count_nonzero(size <= level.window_ms)),
        perfect=int(np.count_nonzero(size <= HARD_WINDOW_MS)),
        good=int(np.count_nonzero((size > HARD_WINDOW_MS) & (size <= EASY_WINDOW_MS))),
        ok=int(np.count_nonzero(size > EASY_WINDOW_MS)),
        mean_offset_ms=float(off.mean()) if off.size else None,
        sd_offset_ms=float(off.std(ddof=1)) if off.size > 1 else (0.0 if off.size else None),
        median_offset_ms=float(np.median(off)) if off.size else None,
        mean_velocity_diff=float(vel.mean()) if vel.size else None,
    )


def summary(matching: Matching, level: Level = Level.EASY) -> dict[str, Any]:
    """The JSON object of ``practice score --json``: the take's tally, ``per_piece`` (piece →
    the same fields, with the extra notes of that piece), and ``notes`` (one per reference
    note: time_s, piece, result, grade, offset_ms, velocity_diff)."""
    notes = matching.notes
    whole = tally(notes, matching.extra.size, level)
    extra_piece = matching.played_piece[matching.extra]
    per_piece: dict[str, Any] = {}
    codes = sorted(set(notes["piece"].tolist()) | set(extra_piece.tolist()))
    for code in codes:
        rows = notes[notes["piece"] == code]
        extra = int(np.count_nonzero(extra_piece == code))
        per_piece[PIECES[code]] = tally(rows, extra, level).as_json()
    grades = note_grades(notes)
    listed = []
    for row, grade in zip(notes, grades, strict=True):
        off = float(row["offset_ms"])
        missed = row["result"] == Result.MISSED
        listed.append(
            {
                "time_s": round(float(row["time_s"]), 6),
                "piece": PIECES[int(row["piece"])],
                "result": RESULT_NAMES[int(row["result"])],
                "grade": grade,
                "offset_ms": None if np.isnan(off) else round(off, 3),
                "velocity_diff": None if missed else int(row["velocity_diff"]),
            }
        )
    extras = [
        {"time_s": round(float(matching.played_s[j]), 6), "piece": PIECES[int(piece)]}
        for j, piece in zip(matching.extra.tolist(), extra_piece.tolist(), strict=True)
    ]
    return {
        **whole.as_json(),
        **windows_json(matching.window_ms, level),
        "per_piece": per_piece,
        "notes": listed,
        "extra_notes": extras,
    }


def windows_json(match_window_ms: float, level: Level) -> dict[str, Any]:
    """The windows and grade bounds of a judged take, named as in the module docstring."""
    return {
        "level": level.value,
        "match_window_ms": float(match_window_ms),
        "on_time_window_ms": level.window_ms,
        "grade_limits_ms": {
            "perfect": HARD_WINDOW_MS,
            "good": EASY_WINDOW_MS,
            "ok": float(match_window_ms),
        },
    }


def window_words(result: dict[str, Any]) -> dict[str, str]:
    """Each window of ``result`` (a :func:`summary`) as a person reads it, by the key it bounds:
    ``hits``, ``on_time``, and each grade. Text, HTML report and JSON say the same numbers."""
    limits = result["grade_limits_ms"]
    words = {grade: f"≤ {limits[grade]:g} ms" for grade in ("perfect", "good", "ok")}
    words["hits"] = f"match window ±{result['match_window_ms']:g} ms"
    words["on_time"] = f"on time ±{result['on_time_window_ms']:g} ms, {result['level']}"
    return words
