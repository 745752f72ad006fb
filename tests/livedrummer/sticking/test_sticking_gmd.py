"""Whole-corpus check on a sample of the Groove MIDI Dataset (skipped where it is absent).

Every 12th file (about 100 files, 37k notes, a few seconds): optimal has no more crossings and
fewer too-fast strokes than every seed, and leaves nothing out unless three hands were needed
or two hands would have struck one hi-hat at once (Kragtwijk et al. §4.2).
"""

from __future__ import annotations

import pytest
from test_sticking_helpers import GMD

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking import metrics
from livedrummer.sticking.strategy import STRATEGIES, assign

FILES = sorted(GMD.rglob("*.mid"))[::12] if GMD.exists() else []


@pytest.mark.skipif(not FILES, reason="Groove MIDI Dataset not present")
def test_optimal_beats_the_seeds_on_real_performances() -> None:
    kit = load_kit("rock5")
    note_map = load_note_map("roland-td")
    perfs = [read_midi_file(f, note_map) for f in FILES]
    score: dict[str, tuple[int, int]] = {}
    for name in STRATEGIES:
        cross = fast = 0
        for p in perfs:
            result = assign(p.onsets, kit, name, beat_s=p.grid.beat_s)
            cross += int(metrics.crossings(result, kit).sum())
            fast += int(metrics.too_fast(result, kit).sum())
            if name == "optimal":
                for i in metrics.dropped(result).nonzero()[0].tolist():
                    why = result.reasons[i]
                    assert "more than two hand notes" in why or "one hi-hat stroke" in why
        score[name] = (cross, fast)
    for name in STRATEGIES:
        if name != "optimal":
            assert score["optimal"][0] <= score[name][0], name
            assert score["optimal"][1] < score[name][1], name
