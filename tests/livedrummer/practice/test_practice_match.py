"""The practice matcher: monotone optimal matching (checked against brute force), the wrong-piece
and extra steps, pieces, and grades."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Zone
from livedrummer.practice.grade import Level, grade_of, summary, tally
from livedrummer.practice.match import (
    PIECE_CODE,
    Result,
    match_take,
    monotone_match,
    parse_pieces,
    piece_codes,
)
from livedrummer.timeline.events import ONSET_DTYPE


def onsets(*rows: tuple[float, str], zone: Zone = Zone.HEAD, velocity: int = 100) -> np.ndarray:
    out = np.zeros(len(rows), dtype=ONSET_DTYPE)
    for i, (t, piece) in enumerate(rows):
        out[i]["time_s"] = t
        out[i]["velocity"] = velocity
        out[i]["instrument"] = INSTRUMENT_CODE[piece]
        out[i]["zone"] = ZONES.index(zone)
        out[i]["hihat"] = HIHATS.index(HiHat.CLOSED if piece == "hihat" else HiHat.NONE)
    return out


def brute(ref: list[float], played: list[float], w: float) -> tuple[int, float]:
    """Best (pairs, -total |offset|) over every monotone matching, by enumeration."""
    best = (0, 0.0)
    n, m = len(ref), len(played)
    for k in range(1, min(n, m) + 1):
        for ri in itertools.combinations(range(n), k):
            for pj in itertools.combinations(range(m), k):
                offs = [abs(played[b] - ref[a]) for a, b in zip(ri, pj, strict=True)]
                if max(offs) <= w:
                    best = max(best, (k, -sum(offs)))
    return best


def test_dp_equals_brute_force_on_random_cases() -> None:
    rng = np.random.default_rng(7)
    for _ in range(300):
        ref = np.sort(rng.uniform(0, 0.6, rng.integers(0, 6)))
        played = np.sort(rng.uniform(0, 0.6, rng.integers(0, 6)))
        pairs = monotone_match(ref, played, 0.1)
        got = (len(pairs), -sum(abs(played[b] - ref[a]) for a, b in pairs))
        want = brute(ref.tolist(), played.tolist(), 0.1)
        assert got[0] == want[0]
        assert got[1] == pytest.approx(want[1], abs=1e-5)
        assert all(abs(played[b] - ref[a]) <= 0.1 for a, b in pairs)
        assert [a for a, _ in pairs] == sorted({a for a, _ in pairs})
        assert [b for _, b in pairs] == sorted({b for _, b in pairs})


def test_not_greedy_count_first() -> None:
    # Greedy nearest-first gives the hit at 0.05 to ref 0.06 (1 ms) and strands ref 0.0;
    # the optimum matches both refs.
    pairs = monotone_match(np.array([0.0, 0.06]), np.array([0.05, 0.15]), 0.1)
    assert pairs == [(0, 0), (1, 1)]


def test_results_wrong_piece_missed_extra() -> None:
    ref = onsets((1.0, "snare"), (2.0, "snare"), (3.0, "kick"), (4.0, "tom1"))
    played = onsets((1.010, "snare"), (2.030, "tom2"), (3.5, "kick"), (4.02, "tom1"), (6.0, "ride"))
    m = match_take(ref, played)
    assert m.notes["result"].tolist() == [Result.HIT, Result.WRONG_PIECE, Result.MISSED, Result.HIT]
    assert m.notes["offset_ms"][0] == pytest.approx(10.0)
    assert m.notes["offset_ms"][3] == pytest.approx(20.0)
    assert sorted(m.extra.tolist()) == [2, 4]  # the late kick (500 ms) and the ride
    s = summary(m)
    assert (s["hits"], s["wrong_piece"], s["missed"], s["extra"]) == (2, 1, 1, 2)
    assert s["mean_offset_ms"] == pytest.approx(15.0)
    assert s["per_piece"]["snare"]["hits"] == 1
    assert s["per_piece"]["ride"]["extra"] == 1
    assert [n["result"] for n in s["notes"]] == ["hit", "wrong_piece", "missed", "hit"]


def test_same_piece_hit_beats_wrong_piece() -> None:
    # A tom hit nearer in time does not steal a snare note that has a snare hit in the window.
    ref = onsets((1.0, "snare"))
    played = onsets((0.999, "tom1"), (1.060, "snare"))
    m = match_take(ref, played)
    assert m.notes["result"][0] == Result.HIT
    assert m.extra.tolist() == [0]


def test_zones_same_piece_pedal_its_own() -> None:
    ref = onsets((1.0, "snare"), zone=Zone.HEAD)
    rim = onsets((1.0, "snare"), zone=Zone.RIM)
    assert match_take(ref, rim).notes["result"][0] == Result.HIT
    hat = onsets((1.0, "hihat"), zone=Zone.BOW)
    pedal = onsets((1.0, "hihat"), zone=Zone.PEDAL)
    assert piece_codes(pedal)[0] == PIECE_CODE["hihat_pedal"]
    assert match_take(hat, pedal).notes["result"][0] == Result.WRONG_PIECE


def test_pieces_judge_only_those() -> None:
    ref = onsets((1.0, "snare"), (1.5, "kick"))
    played = onsets((1.0, "kick"), (3.0, "kick"), (4.0, "snare"))
    m = match_take(ref, played, pieces=parse_pieces("snare"))
    assert m.notes.size == 1 and m.notes["result"][0] == Result.WRONG_PIECE
    assert m.extra.tolist() == [2]  # the far kick is not judged, the far snare is extra
    with pytest.raises(ValueError, match="unknown piece 'snar'"):
        parse_pieces("snar")


def test_grades_and_score() -> None:
    assert [grade_of(x) for x in (-20, 20.5, -40, 41)] == ["perfect", "good", "good", "ok"]
    ref = onsets((1.0, "snare"), (2.0, "snare"), (3.0, "snare"), (4.0, "snare"))
    played = onsets((1.010, "snare"), (2.030, "snare"), (3.070, "snare"), (9.0, "snare"))
    m = match_take(ref, played)
    t = tally(m.notes, m.extra.size)
    assert (t.perfect, t.good, t.ok, t.missed, t.extra) == (1, 1, 1, 1, 1)
    assert t.score == pytest.approx(100 * (1 + 0.7 + 0.4) / 5)
    assert t.accuracy_pct == pytest.approx(100 * 2 / 5)
    hard = tally(m.notes, m.extra.size, Level.HARD)
    assert hard.accuracy_pct == pytest.approx(100 * 1 / 5)


def test_long_dense_take_is_fast_and_exact() -> None:
    # 16ths at 200 bpm (75 ms apart, window 100 ms): one long chain of candidates.
    rng = np.random.default_rng(3)
    ref = np.arange(4000) * 0.075
    played = np.sort(ref + rng.normal(0, 0.012, ref.size))
    pairs = monotone_match(ref, played, 0.1)
    assert len(pairs) == ref.size
    assert all(a == b for a, b in pairs)
