"""The seed strategies behave as their papers describe, flaws included."""

from __future__ import annotations

import numpy as np
from test_sticking_helpers import onsets

from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking import metrics
from livedrummer.sticking.kragtwijk import kragtwijk_basic, kragtwijk_pair
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED
from livedrummer.sticking.smed import smed
from livedrummer.sticking.strategy import StrategyError, assign

RH, LH = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH]


def test_basic_uses_default_hands_and_flips_the_middle_of_fast_triplets() -> None:
    kit = load_kit("rock5")
    slow = onsets((0.0, "snare"), (0.5, "hihat"), (1.0, "snare"))
    assert kragtwijk_basic(slow, kit).limb.tolist() == [LH, RH, LH]
    fast = onsets((0.0, "snare"), (0.05, "snare"), (0.10, "snare"))
    assert kragtwijk_basic(fast, kit).limb.tolist() == [LH, RH, LH]


def test_basic_deletes_the_third_simultaneous_hand_note() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "snare"), (0.0, "tom1"), (0.0, "ride"))
    result = kragtwijk_basic(on, kit)
    assert np.count_nonzero(result.limb == NOT_PLAYED) == 1
    assert "more than two" in next(iter(result.reasons.values()))


def test_basic_crosses_on_a_fast_hihat_ride_hihat_and_pair_does_not() -> None:
    # the paper's own example: basic gives the ride to the left hand; pair fixes it
    kit = load_kit("rock5")
    on = onsets((0.0, "hihat"), (0.06, "ride"), (0.12, "hihat"))
    basic = kragtwijk_basic(on, kit)
    assert basic.limb[1] == LH
    assert metrics.crossings(basic, kit).any()
    pair = kragtwijk_pair(on, kit)
    assert pair.limb[1] == RH
    assert pair.limb[0] == LH and pair.limb[2] == LH


def test_pair_keeps_one_hihat_stroke_per_instant() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "hihat"), (0.0, "hihat"), (0.0, "snare"))
    result = kragtwijk_pair(on, kit)
    assert np.count_nonzero(result.limb == NOT_PLAYED) == 1
    assert any("one hi-hat" in r for r in result.reasons.values())


def test_pair_weight_fades_with_time() -> None:
    kit = load_kit("rock5")
    # the pair table says crash2 right, snare left; far apart, default hands rule instead
    near = kragtwijk_pair(onsets((0.0, "snare"), (0.001, "crash2")), kit)
    assert near.limb.tolist() == [LH, RH]
    far = kragtwijk_pair(onsets((0.0, "tom1"), (5.0, "tom2")), kit)
    assert far.limb.tolist() == [RH, RH]


def test_smed_splits_quick_notes_on_different_drums_by_side() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "tom3"), (0.05, "tom1"))  # floor tom (right) then high tom (left)
    assert smed(on, kit).limb.tolist() == [RH, LH]
    ride = onsets((0.0, "ride"), (0.05, "ride"))
    assert smed(ride, kit).limb[0] == RH


def test_unknown_strategy_is_an_error_naming_the_known_ones() -> None:
    kit = load_kit("rock5")
    try:
        assign(onsets((0.0, "snare")), kit, "random")
    except StrategyError as exc:
        assert "random" in str(exc) and "optimal" in str(exc)
    else:
        raise AssertionError("no error")
