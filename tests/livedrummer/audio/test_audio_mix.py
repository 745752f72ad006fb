"""The synthesized drum kit and the offline mixer, cymbal chokes included."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from livedrummer.audio.mix import GRAB_FADE_S, choke_cut_s, mix_onsets, voice_for
from livedrummer.audio.synth import LAYERS, SAMPLE_RATE, layer_for, voice_layers, voice_names
from livedrummer.body.sample import kit_choke_times
from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Zone
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.events import ONSET_DTYPE

KIT = load_kit("rock5")


def onsets(*rows: tuple[float, str, int, Zone, HiHat]) -> np.ndarray:
    out = np.zeros(len(rows), ONSET_DTYPE)
    for i, (t, inst, vel, zone, hat) in enumerate(rows):
        out[i]["time_s"], out[i]["velocity"] = t, vel
        out[i]["instrument"] = INSTRUMENT_CODE[inst]
        out[i]["zone"], out[i]["hihat"] = ZONES.index(zone), HIHATS.index(hat)
    return out


def centroid(x: np.ndarray) -> float:
    spec = np.abs(np.fft.rfft(x))
    freqs = np.fft.rfftfreq(x.size, 1 / SAMPLE_RATE)
    return float((spec * freqs).sum() / spec.sum())


@pytest.mark.parametrize("voice", [*voice_names(), "tom@120"])
def test_layers_get_louder_and_brighter(voice: str) -> None:
    layers = voice_layers(voice)
    assert len(layers) == len(LAYERS)
    peaks = [float(np.abs(x).max()) for x in layers]
    assert all(a < b for a, b in itertools.pairwise(peaks))
    assert peaks[-1] <= 1.0
    for x in layers:
        assert x.dtype == np.float32 and np.all(np.isfinite(x))
        assert abs(x[-1]) < 1e-3  # faded out: no click at the end


@pytest.mark.parametrize("voice", ["kick", "snare", "hihat_closed", "crash", "tom@120"])
def test_harder_layers_are_brighter(voice: str) -> None:
    soft, hard = voice_layers(voice)[0], voice_layers(voice)[-1]
    assert centroid(hard[:4800]) > centroid(soft[:4800])


def test_layer_choice_reaches_the_velocity() -> None:
    for v in (1, 39, 40, 41, 100, 127):
        i, gain = layer_for(v)
        assert LAYERS[i] >= v and (i == 0 or LAYERS[i - 1] < v)
        assert 0 < gain <= 1.0


def test_voices_follow_zone_and_articulation() -> None:
    assert voice_for("hihat", Zone.EDGE, HiHat.OPEN) == "hihat_open"
    assert voice_for("hihat", Zone.PEDAL, HiHat.PEDAL) == "hihat_pedal"
    assert voice_for("snare", Zone.CROSS_STICK, HiHat.NONE) == "click"
    assert voice_for("ride", Zone.BELL, HiHat.NONE) == "ride_bell"
    hi, lo = (
        voice_for("tom1", Zone.HEAD, HiHat.NONE, KIT),
        voice_for("tom3", Zone.HEAD, HiHat.NONE, KIT),
    )
    assert float(hi[4:]) > float(lo[4:])  # the smaller tom sounds higher


def test_each_stroke_starts_on_its_sample() -> None:
    times = [0.25, 0.8, 1.3]
    on = onsets(*((t, "kick", 100, Zone.HEAD, HiHat.NONE) for t in times))
    mix = mix_onsets(on, 2.0, KIT)
    assert mix.shape == (2 * SAMPLE_RATE, 2) and mix.dtype == np.float32
    mono = np.abs(mix).sum(axis=1)
    first = int(np.flatnonzero(mono)[0])
    assert abs(first - round(0.25 * SAMPLE_RATE)) <= 1
    for t in times:
        start = round(t * SAMPLE_RATE)
        before, after = mono[start - 240 : start], mono[start : start + 240]
        assert after.max() > 0.1 and after.max() > 2 * before.max()


def test_closed_hihat_chokes_the_open_one() -> None:
    open_only = onsets((0.1, "hihat", 100, Zone.EDGE, HiHat.OPEN))
    choked = onsets(
        (0.1, "hihat", 100, Zone.EDGE, HiHat.OPEN), (0.3, "hihat", 1, Zone.BOW, HiHat.CLOSED)
    )
    a, b = mix_onsets(open_only, 1.0, KIT), mix_onsets(choked, 1.0, KIT)
    late = slice(int(0.5 * SAMPLE_RATE), None)
    assert np.abs(a[late]).max() > 0.01
    assert np.abs(b[late]).max() < 0.2 * np.abs(a[late]).max()


def test_panning_puts_the_hihat_left_and_the_floor_tom_right() -> None:
    hat = mix_onsets(onsets((0.0, "hihat", 100, Zone.BOW, HiHat.CLOSED)), 0.5, KIT)
    tom = mix_onsets(onsets((0.0, "tom3", 100, Zone.HEAD, HiHat.NONE)), 0.5, KIT)
    assert np.abs(hat[:, 0]).sum() > 1.5 * np.abs(hat[:, 1]).sum()
    assert np.abs(tom[:, 1]).sum() > 1.5 * np.abs(tom[:, 0]).sum()


def test_loud_mixes_are_scaled_not_clipped() -> None:
    on = onsets(
        *(
            (0.0, inst, 127, Zone.HEAD, HiHat.NONE)
            for inst in ("kick", "snare", "crash1", "crash2", "tom1", "tom2")
        )
    )
    mix = mix_onsets(on, 1.0, KIT)
    assert 0.5 < np.abs(mix).max() <= 0.9 + 1e-6


def grabs(**times: list[float]) -> list[np.ndarray]:
    """Chokes per piece of KIT: ``grabs(crash1=[0.6])``."""
    names = [p.name for p in KIT.pieces]
    assert set(times) <= set(names), times
    return [np.asarray(times.get(name, []), np.float64) for name in names]


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x, dtype=np.float64)))) if x.size else 0.0


def test_a_grab_stops_the_crash_after_a_short_fade_and_the_next_stroke_rings() -> None:
    sr, grab, again = SAMPLE_RATE, 0.6, 1.3
    on = onsets(
        (0.1, "crash1", 90, Zone.BOW, HiHat.NONE), (again, "crash1", 90, Zone.BOW, HiHat.NONE)
    )
    free = mix_onsets(on, 2.0, KIT)
    choked = mix_onsets(on, 2.0, KIT, chokes=grabs(crash1=[grab]))
    g, f, a = round(grab * sr), round(GRAB_FADE_S * sr), round(again * sr)
    # bit-exact by design: up to the grab both mixes run the same code on the same samples
    np.testing.assert_array_equal(choked[:g], free[:g])  # untouched up to the grab
    assert rms(free[g + f : a]) > 0.02  # a crash rings for seconds ...
    assert not choked[g + f : a].any()  # ... and after the grab's fade it is silent
    # the fade: the choked sound is the free one times a ramp from 1 to 0 over GRAB_FADE_S,
    # so it never jumps more than the crash itself does from one sample to the next
    gain = choked[g : g + f, 0] / free[g : g + f, 0]
    np.testing.assert_allclose(gain, np.linspace(1.0, 0.0, f), atol=1e-5)
    assert (
        np.abs(np.diff(choked[g - f : g + f + 1, 0])).max()
        <= np.abs(np.diff(free[g - f : g + f + 1, 0])).max() + 1e-6
    )
    # the stroke after the grab sounds in full (the free mix also has the first one's tail)
    alone = mix_onsets(on[1:], 2.0, KIT)
    np.testing.assert_allclose(choked[a:], alone[a:], atol=1e-6)


def test_a_grab_stops_only_its_own_cymbal() -> None:
    both = onsets(
        (0.1, "crash1", 80, Zone.BOW, HiHat.NONE), (0.1, "ride", 80, Zone.BOW, HiHat.NONE)
    )
    choked = mix_onsets(both, 1.5, KIT, chokes=grabs(crash1=[0.5]))
    ride = mix_onsets(both[1:], 1.5, KIT)
    after = round((0.5 + GRAB_FADE_S) * SAMPLE_RATE)
    np.testing.assert_allclose(choked[after:], ride[after:], atol=1e-6)
    assert rms(ride[after:]) > 0.01


def test_choke_rule_a_grab_stops_what_rings_at_or_before_it() -> None:
    on = onsets(
        *((t, "crash1", 100, Zone.BOW, HiHat.NONE) for t in (0.1, 0.5, 0.9)),
        (0.2, "crash2", 100, Zone.BOW, HiHat.NONE),
    )
    cut = choke_cut_s(on, KIT, grabs(crash1=[0.5, 0.7]))
    assert cut.tolist() == [0.5, 0.5, np.inf, np.inf]  # a grab on the stroke's own time too
    assert np.isinf(choke_cut_s(on, KIT, None)).all()
    with pytest.raises(ValueError, match="kit"):
        mix_onsets(on, 1.0, None, chokes=grabs(crash1=[0.5]))


def test_drummer6s_grab_stops_the_crash_in_the_mix(groove_dir: Path) -> None:
    # GMD drummer6 grabs crash 1 (Roland notes 49 and 55) 0.43 s after its last stroke.
    path = groove_dir / "drummer6" / "session3" / "2_rock_100_beat_4-4.mid"
    note_map = load_note_map("roland-td")
    perf = read_midi_file(path, note_map)
    chokes = kit_choke_times(perf.controls, note_map, KIT)
    crash = [p.name for p in KIT.pieces].index("crash1")
    assert chokes[crash].size == 2 and not any(c.size for k, c in enumerate(chokes) if k != crash)
    grab = float(chokes[crash][0])
    on = perf.onsets[perf.onsets["time_s"] > grab - 5.0]  # the last bars: a fast mix
    dur = perf.duration_s + 2.0
    after = slice(round((grab + 0.01) * SAMPLE_RATE), round((grab + 0.3) * SAMPLE_RATE))
    is_crash = on["instrument"] == INSTRUMENT_CODE["crash1"]
    free_crash = mix_onsets(on[is_crash], dur, KIT)
    assert rms(free_crash[after]) > 0.01
    assert not mix_onsets(on[is_crash], dur, KIT, chokes=chokes)[after].any()
    # in the full mix what sounds after the grab is everything but the crash
    rest = mix_onsets(on[~is_crash], dur, KIT)
    full = mix_onsets(on, dur, KIT, chokes=chokes)
    np.testing.assert_allclose(full[after], rest[after], atol=1e-6)
    assert rms(mix_onsets(on, dur, KIT)[after] - full[after]) > 0.5 * rms(free_crash[after])
