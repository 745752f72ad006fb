"""The synthesized drum kit and the offline mixer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from livedrummer.audio.mix import mix_onsets, voice_for
from livedrummer.audio.synth import LAYERS, SAMPLE_RATE, layer_for, voice_layers, voice_names
from livedrummer.events import ONSET_DTYPE
from livedrummer.kitfile import load_kit
from livedrummer.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Zone

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
    hi, lo = voice_for("tom1", Zone.HEAD, HiHat.NONE, KIT), voice_for("tom3", Zone.HEAD,
                                                                      HiHat.NONE, KIT)  # fmt: skip
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
    choked = onsets((0.1, "hihat", 100, Zone.EDGE, HiHat.OPEN),
                    (0.3, "hihat", 1, Zone.BOW, HiHat.CLOSED))  # fmt: skip
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
    on = onsets(*((0.0, inst, 127, Zone.HEAD, HiHat.NONE)
                  for inst in ("kick", "snare", "crash1", "crash2", "tom1", "tom2")))  # fmt: skip
    mix = mix_onsets(on, 1.0, KIT)
    assert 0.5 < np.abs(mix).max() <= 0.9 + 1e-6
