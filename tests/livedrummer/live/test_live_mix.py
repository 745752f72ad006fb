"""The live kit against its offline twin: the same onsets, block by block, the same samples."""

from __future__ import annotations

import numpy as np

from livedrummer.audio.live_mix import LiveMixer
from livedrummer.audio.mix import mix_onsets
from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import INSTRUMENTS
from livedrummer.timeline.events import ONSET_DTYPE

SR = 48_000


def some_onsets() -> np.ndarray:
    names = ["kick", "hihat", "snare", "hihat", "tom1", "hihat", "ride", "crash1", "hihat"]
    rows = np.zeros(len(names), ONSET_DTYPE)
    rows["time_s"] = 0.05 + 0.11 * np.arange(len(names))
    rows["instrument"] = [INSTRUMENTS.index(n) for n in names]
    rows["velocity"] = [40, 30, 50, 25, 45, 35, 30, 40, 60]
    return rows


def test_the_live_mixer_is_the_offline_mix_block_by_block() -> None:
    kit = load_kit("rock5")
    onsets = some_onsets()
    offline = mix_onsets(onsets, 1.5, kit, SR)
    assert np.abs(offline).max() < 0.9  # not scaled for headroom: the twins must agree exactly
    live = LiveMixer(kit, SR)
    blocks, k = [], 0
    for size in [128, 333, 512, 64] * 80:  # onsets added about 30 ms before they sound
        while k < onsets.size and round(onsets["time_s"][k] * SR) < live.rendered + size + 1440:
            live.add(onsets[k], round(float(onsets["time_s"][k]) * SR))
            k += 1
        blocks.append(live.render(size))
    got = np.concatenate(blocks)[: len(offline)]
    assert k == onsets.size and len(got) == len(offline)
    end = len(offline) - round(0.01 * SR)  # the offline track fades out what its end cuts
    assert np.max(np.abs(got[:end] - offline[:end])) < 1e-5
    assert not live.voices or all(v.start + v.length > live.rendered for v in live.voices)


def test_a_late_onset_starts_where_it_is_put_and_loud_sums_are_clipped() -> None:
    live = LiveMixer(None, SR)
    live.render(1000)
    row = some_onsets()[0]
    row["velocity"] = 127
    for _ in range(8):  # eight full-velocity kicks on one sample: far over full scale
        live.add(row, 1010)
    out = live.render(600)
    assert np.all(out[:10] == 0) and np.any(out[10:20] != 0)
    assert live.clipped > 0 and np.abs(out).max() <= 1.0
