"""The judging rules: crossings and too-fast strokes, on hand-built stickings."""

from __future__ import annotations

import numpy as np
from test_sticking_helpers import onsets

from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking import metrics
from livedrummer.sticking.prepare import piece_table
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED, Sticking

RH, LH = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH]


def sticking(kit: Kit, notes: list[tuple[float, str, int]]) -> Sticking:
    on = onsets(*[(t, name) for t, name, _ in notes])
    limb = np.array([h for _, _, h in sorted(notes, key=lambda n: n[0])], dtype=np.int8)
    return Sticking(on, limb, piece_table(kit)[on["instrument"]], {}, "test", kit.name)


def test_high_tom_right_over_floor_tom_left_is_a_crossing() -> None:
    kit = load_kit("rock5")
    s = sticking(kit, [(0.0, "tom1", RH), (0.0, "tom3", LH)])
    assert metrics.crossings(s, kit).all()
    ok = sticking(kit, [(0.0, "tom1", LH), (0.0, "tom3", RH)])
    assert not metrics.crossings(ok, kit).any()


def test_right_hand_on_the_hihat_over_the_snare_is_conventional_and_mirrors() -> None:
    right, left = load_kit("rock5"), load_kit("rock5-left")
    assert not metrics.crossings(
        sticking(right, [(0.0, "hihat", RH), (0.0, "snare", LH)]), right
    ).any()
    assert not metrics.crossings(
        sticking(left, [(0.0, "hihat", LH), (0.0, "snare", RH)]), left
    ).any()
    # the left hand reaching over to the ride is not
    s = sticking(right, [(0.0, "snare", RH), (0.0, "ride", LH)])
    assert metrics.crossings(s, right).all()


def test_an_idle_hand_does_not_count_in_the_stance() -> None:
    kit = load_kit("rock5")
    s = sticking(kit, [(0.0, "tom3", LH), (2.0, "tom1", RH)])
    assert not metrics.crossings(s, kit).any()


def test_too_fast_single_and_double_strokes() -> None:
    kit = load_kit("rock5")  # snare min gap 0.10
    single = sticking(kit, [(0.0, "snare", LH), (0.08, "tom1", LH)])
    assert metrics.too_fast(single, kit).tolist() == [False, True]
    double = sticking(kit, [(0.0, "snare", LH), (0.06, "snare", LH), (0.20, "snare", LH)])
    assert not metrics.too_fast(double, kit).any()
    triple = sticking(kit, [(0.0, "snare", LH), (0.06, "snare", LH), (0.12, "snare", LH)])
    assert metrics.too_fast(triple, kit).tolist() == [False, False, True]
    hands = sticking(kit, [(0.0, "snare", LH), (0.02, "snare", RH), (0.04, "snare", LH)])
    assert metrics.too_fast(hands, kit).tolist() == [False, False, True]


def test_dropped_and_accuracy() -> None:
    kit = load_kit("rock5")
    s = sticking(kit, [(0.0, "snare", NOT_PLAYED), (0.5, "hihat", RH), (1.0, "snare", LH)])
    assert metrics.dropped(s).tolist() == [True, False, False]
    teacher = np.array([LH, RH, RH], dtype=np.int8)
    assert metrics.accuracy(s, teacher) == (1, 3)
