"""Expression (SMED §4.1.1): share redistribution and strict TOML presets."""

from __future__ import annotations

from pathlib import Path

import pytest

from livedrummer.body.expression import (
    Expression,
    expression_to_toml,
    load_expression,
    redistribute,
)
from livedrummer.errors import PresetError


def test_moving_one_share_moves_the_others_in_proportion() -> None:
    out = redistribute((0.5, 0.3, 0.2), 0, 0.7)
    assert out[0] == 0.7
    assert sum(out) == pytest.approx(1.0)
    assert out[1] / out[2] == pytest.approx(0.3 / 0.2)
    assert out[1] + out[2] == pytest.approx(0.3)


def test_gains_scale_amplitudes_and_time() -> None:
    e = Expression(amplitude_gain=2.0, amplitude_shares=(0.5, 0.3, 0.2))
    assert e.joint_amplitude_rad(1.0) == pytest.approx((1.0, 0.6, 0.4))
    assert Expression().joint_time_scale() == pytest.approx((1.0, 1.0, 1.0))
    fast = Expression(frequency_gain=2.0).joint_time_scale()
    assert fast == pytest.approx((0.5, 0.5, 0.5))


@pytest.mark.parametrize("name", ["default", "relaxed", "energetic"])
def test_bundled_presets_load(name: str) -> None:
    e = load_expression(name)
    assert isinstance(e, Expression)
    assert sum(e.amplitude_shares) == pytest.approx(1.0)


def test_preset_round_trips_through_toml(tmp_path: Path) -> None:
    e = Expression(amplitude_gain=1.2, amplitude_shares=(0.6, 0.3, 0.1), head_amplitude_deg=9)
    path = tmp_path / "mine.toml"
    path.write_text(expression_to_toml(e))
    assert load_expression(str(path)) == e


def test_unknown_key_and_bad_shares_name_file_and_key(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[expression]\namplitude_gian = 1.0\n")
    with pytest.raises(
        PresetError, match=r"bad.toml.*amplitude_gian.*did you mean 'amplitude_gain'"
    ):
        load_expression(str(bad))
    bad.write_text("[expression]\namplitude_shares = [0.5, 0.5, 0.5]\n")
    with pytest.raises(PresetError, match=r"amplitude_shares.*summing to 1"):
        load_expression(str(bad))
    with pytest.raises(PresetError, match="no expression preset named 'nope'"):
        load_expression("nope")
