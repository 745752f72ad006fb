"""SMED's controls: one table of expression parameters, each a preset key and a live knob that
moves the drummer (and only the pieces it names)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from livedrummer.body.animation import animate, hihat_openness
from livedrummer.body.expression import (
    PARAMS,
    Expression,
    Param,
    expression_to_toml,
    load_expression,
    param_value,
    params_markdown,
    with_param,
)
from livedrummer.body.rig import Rig
from livedrummer.body.sample import sample_poses
from livedrummer.errors import PresetError
from livedrummer.live.synth import LiveSynth
from livedrummer.sticking.online import stick_online
from livedrummer.sticking.result import Sticking
from livedrummer.timeline.events import CONTROL_DTYPE
from livedrummer.timeline.performance import Performance

REPO = Path(__file__).resolve().parents[3]


def moved(p: Param) -> float:
    """A value far from the default: the low end if there is room below it, else the high."""
    return p.lo if p.lo < p.default else p.hi


def test_the_table_s_defaults_are_the_expression_s() -> None:
    for p in PARAMS:
        assert param_value(Expression(), p.name) == pytest.approx(p.default), p.name
        assert p.lo <= p.default <= p.hi, p.name
    assert len({p.name for p in PARAMS}) == len(PARAMS)


def test_moving_one_share_rescales_the_others_as_smed_does() -> None:
    e = with_param(Expression(), "amplitude_wrist", 0.75)
    assert e.amplitude_shares == pytest.approx((0.75, 0.25 * 0.25 / 0.45, 0.25 * 0.20 / 0.45))
    e = with_param(e, "frequency_shoulder", 0.5)
    assert e.frequency_shares == pytest.approx((0.25, 0.25, 0.5))
    with pytest.raises(ValueError, match=r"head_amplitude_deg: expected 0\.\.30 \(got 45"):
        with_param(e, "head_amplitude_deg", 45.0)
    with pytest.raises(ValueError, match="no expression parameter named 'head_amp'"):
        with_param(e, "head_amp", 1.0)
    with pytest.raises(ValueError, match="expected"):
        with_param(e, "ctb_bias", float("nan"))


@pytest.fixture(scope="module")
def window(rig: Rig, groove: Performance) -> tuple[Sticking, np.ndarray, np.ndarray]:
    onsets = groove.onsets[groove.onsets["time_s"] < 4.0].copy()
    sticking = stick_online(onsets, rig.kit, 0.03)
    times = np.arange(0.5, 3.5, 1 / 60)
    return sticking, groove.grid.beat_s, times


@pytest.mark.parametrize("param", PARAMS, ids=[p.name for p in PARAMS])
def test_each_parameter_moves_the_drummer(
    rig: Rig, window: tuple[Sticking, np.ndarray, np.ndarray], param: Param
) -> None:
    """Moved to an end of its range, every parameter changes the poses, except the amplitude
    of a piece kind that is not played (then nothing changes at all)."""
    sticking, beats, times = window
    openness = hihat_openness(sticking.onsets, np.zeros(0, CONTROL_DTYPE))

    def poses(e: Expression) -> np.ndarray:
        anim = animate(rig, sticking, beats, openness, e)
        rows: np.ndarray = sample_poses(anim, sticking, times)["rotation"]
        return rows

    change = np.abs(poses(with_param(Expression(), param.name, moved(param))) - poses(Expression()))
    played = {rig.kit.pieces[i].kind.value for i in sticking.piece[sticking.piece >= 0]}
    kind = param.name.removeprefix("amplitude_")
    if (
        param.unit == "x"
        and kind in {p.name.removeprefix("amplitude_") for p in PARAMS}
        and (kind not in played and kind != "gain")
    ):
        # bit-exact by design: a piece's amplitude that no note plays never enters the sums
        assert change.max() == 0.0, f"{param.name}: moved poses though no {kind} is played"
    else:
        assert change.max() > 0.005, f"{param.name}: the drummer did not move ({change.max()})"


def test_every_parameter_is_a_preset_key(tmp_path: Path) -> None:
    e = Expression()
    for p in PARAMS:
        e = with_param(e, p.name, (moved(p) + p.default) / 2)
    path = tmp_path / "all.toml"
    path.write_text(expression_to_toml(e))
    back = load_expression(str(path))
    for p in PARAMS:
        assert param_value(back, p.name) == pytest.approx(param_value(e, p.name)), p.name
    path.write_text("[expression]\namplitude_hihat = 0.6\namplitude_wrist = 0.7\n")
    one = load_expression(str(path))
    assert one.piece_gain("hihat") == 0.6 and sum(one.amplitude_shares) == pytest.approx(1.0)
    path.write_text("[expression]\nhead_frequency = 9\n")
    with pytest.raises(PresetError, match=r"all.toml.*head_frequency: must be <= 4"):
        load_expression(str(path))


def test_the_presets_page_documents_the_table() -> None:
    """The documentation's presets page (generated at every docs build) carries this table."""
    spec = importlib.util.spec_from_file_location("docs_hooks", REPO / "deploy" / "docs_hooks.py")
    assert spec is not None and spec.loader is not None
    hooks = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hooks)
    assert params_markdown() in hooks.format_markdown("reference/presets.md")


def test_a_live_parameter_is_eased_in(rig: Rig) -> None:
    synth = LiveSynth(rig)
    synth.set_param("amplitude_hihat", 0.5, 100.0)
    assert synth.style.target.piece_gain("hihat") == 0.5
    change = synth.style.change(100.0)
    assert change is not None and change.old == Expression()
    with pytest.raises(ValueError, match="amplitude_hihat"):
        synth.set_param("amplitude_hihat", 5.0, 100.1)
