"""The live style: a preset changed while the drummer plays is eased in without joint jumps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from livedrummer.body.expression import Expression, load_expression
from livedrummer.body.rig import Rig
from livedrummer.live.style import StyleRamp, mix_expression
from livedrummer.live.synth import LiveSynth, PoseBatch, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.timeline.performance import Performance
from tests.services.cli.test_live_up import launch

START = 5000.0  # onsets live on the shared clock, far from 0
SWITCH = START + 2.5  # the clock time the preset changes


def play_switching(synth: LiveSynth, onsets: np.ndarray, to: Expression, at_s: float) -> PoseBatch:
    """Feed onsets at their times and poll at 120 Hz as the service does, switching the
    expression at clock time ``at_s``; the samples as a display keeps them."""
    tick = 1 / 120
    now = float(onsets["time_s"][0]) - 0.2
    end = float(onsets["time_s"][-1]) + 0.3
    i, track, switched = 0, PoseTrack(keep_s=end - now + 1.0), False
    while now < end:
        if not switched and now >= at_s:
            synth.set_expression(to, now)
            switched = True
        while i < onsets.size and onsets["time_s"][i] <= now:
            synth.process(onsets[i])
            i += 1
        batch = synth.poses_until(now)
        track.add(batch.show_s, batch.rows)
        now += tick
    return PoseBatch(track.show_s.copy(), track.rows.copy())


def joint_speed(out: PoseBatch) -> tuple[np.ndarray, np.ndarray]:
    """The largest joint angular speed (rad/s, from the local rotations) between the poses a
    240 Hz display would show (the latest sample at or before each frame), by frame time."""
    step = 1 / 240
    frames = np.arange(out.show_s[0], out.show_s[-1], step)
    shown = np.searchsorted(out.show_s, frames, side="right") - 1
    q = out.rows["rotation"][shown].astype(np.float64)
    dot = np.abs(np.sum(q[1:] * q[:-1], axis=-1)).clip(0.0, 1.0)
    speed = (2.0 * np.arccos(dot)).max(axis=1) / step
    return frames[1:], speed


def switch_and_surroundings(
    rig: Rig, groove: Performance, params: SynthParams
) -> tuple[float, float]:
    onsets = groove.onsets[groove.onsets["time_s"] < 6.0].copy()
    onsets["time_s"] += START
    synth = LiveSynth(rig, params)
    out = play_switching(synth, onsets, load_expression("energetic"), SWITCH)
    mid, speed = joint_speed(out)
    show = SWITCH + params.delay_s  # the first pose the change can reach
    span = params.style_ramp_s + 2 * params.blend_s + 0.05
    during = (mid >= show - 0.05) & (mid <= show + span)
    around = ((mid >= show - 1.5) & (mid < show - 0.05)) | (
        (mid > show + span) & (mid <= show + span + 1.5)
    )
    return float(speed[during].max()), float(speed[around].max())


def test_a_preset_change_while_playing_moves_no_joint_faster_than_playing(
    rig: Rig, groove: Performance
) -> None:
    during, around = switch_and_surroundings(rig, groove, SynthParams())
    assert during <= around, f"{during:.1f} rad/s during the switch, {around:.1f} around it"


def idle_switch(rig: Rig, params: SynthParams, to: Expression) -> tuple[float, float]:
    """With nothing played (the drummer breathes), the largest joint speed while ``to`` is
    eased in and around it."""
    synth = LiveSynth(rig, params)
    now, track, switched = START, PoseTrack(keep_s=20.0), False
    while now < START + 4.5:
        if not switched and now >= SWITCH:
            synth.set_expression(to, now)
            switched = True
        batch = synth.poses_until(now)
        track.add(batch.show_s, batch.rows)
        now += 1 / 120
    mid, speed = joint_speed(PoseBatch(track.show_s.copy(), track.rows.copy()))
    show, span = SWITCH + params.delay_s, params.style_ramp_s + 0.2
    during = (mid >= show - 0.05) & (mid <= show + span)
    around = (mid >= show - 1.5) & (mid < show - 0.05)
    return float(speed[during].max()), float(speed[around].max())


@pytest.mark.parametrize("ramp_s", [0.5, 0.0])
def test_idle_a_change_moves_no_faster_than_its_ramp(rig: Rig, ramp_s: float) -> None:
    """Back and head amplitudes raised by 40 degrees in all: eased in over ``ramp_s`` along a
    smoothstep (peak speed 1.5 x change / ramp) on top of the breathing; at once (the check
    can fail), a jump."""
    big = Expression(back_amplitude_deg=20.0, head_amplitude_deg=30.0)
    during, breathing = idle_switch(rig, SynthParams(style_ramp_s=ramp_s), big)
    change_rad = np.radians(20.0 - 2.5 + 30.0 - 7.0)
    bound = 1.5 * change_rad / 0.5 + breathing
    if ramp_s > 0:
        assert during <= bound, f"{during:.2f} rad/s during the change (bound {bound:.2f})"
    else:
        assert during > 5 * bound, f"an instant change: only {during:.2f} rad/s"


def test_the_ramp_eases_from_the_old_expression_to_the_new() -> None:
    a, b = Expression(), load_expression("energetic")
    ramp = StyleRamp(a, ramp_s=0.5)
    assert ramp.change(0.0) is None and ramp.target == a
    ramp.set(b, 10.0)
    change = ramp.change(9.0)
    assert change is not None and (change.old, change.new) == (a, b) and ramp.target == b
    w = change.weight(np.array([9.0, 10.0, 10.125, 10.25, 10.5, 11.0]))
    assert w.tolist() == pytest.approx([0.0, 0.0, 0.15625, 0.5, 1.0, 1.0])
    mid = change.expression_at(10.25)
    assert mid == mix_expression(a, b, 0.5)
    assert mid.amplitude_gain == pytest.approx(1.15)
    assert sum(mid.amplitude_shares) == pytest.approx(1.0)
    # a change mid-ramp starts from where the ramp had got to
    ramp.set(a, 10.25)
    again = ramp.change(10.25)
    assert again is not None and again.old == mid and again.new == a
    assert ramp.changes == 2
    assert ramp.change(10.76) is None, "over once every pose still sent lies past it"


def test_up_plays_the_preset_and_strokes_given(gl_ok: None, tmp_path: Path) -> None:
    proc = launch(tmp_path, "--seconds", "3", "--preset", "energetic", "--strokes", "smed")
    out, _ = proc.communicate(timeout=90)
    assert proc.returncode == 0, out[-2000:]
    assert "played with preset energetic, smed strokes" in out, out[-2000:]


def test_a_preset_that_does_not_exist_is_one_line_before_anything_starts(tmp_path: Path) -> None:
    proc = launch(tmp_path, "--preset", "nosuch")
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 2
    assert out.strip().splitlines() == [
        "livedrummer: error: no expression preset named 'nosuch' (known: default, energetic, relaxed)"
    ], out
