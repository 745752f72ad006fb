"""The annotated corpus: optimal against the seeds, online against offline."""

from __future__ import annotations

import numpy as np
import pytest
from test_sticking_helpers import DEMO, TABS

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking import metrics
from livedrummer.sticking.online import stick_online
from livedrummer.sticking.optimal import optimal
from livedrummer.sticking.strategy import STRATEGIES, assign
from livedrummer.sticking.tab import Tab, read_tab

SEEDS = [s for s in STRATEGIES if s != "optimal"]


@pytest.fixture(scope="module")
def tabs() -> list[Tab]:
    assert len(TABS) >= 12
    return [read_tab(f) for f in TABS]


def totals(tabs: list[Tab], strategy: str) -> tuple[float, int, int, int]:
    hit = total = cross = fast = drop = 0
    for tab in tabs:
        kit = load_kit(tab.kit)
        result = assign(tab.onsets, kit, strategy, beat_s=tab.beat_s)
        m, n = metrics.accuracy(result, tab.limbs)
        hit, total = hit + m, total + n
        cross += int(metrics.crossings(result, kit).sum())
        fast += int(metrics.too_fast(result, kit).sum())
        drop += int(metrics.dropped(result).sum())
    return hit / total, cross, fast, drop


def test_every_pattern_is_annotated_throughout(tabs: list[Tab]) -> None:
    for tab in tabs:
        assert tab.onsets.size == tab.limbs.size > 0
        assert np.all(np.diff(tab.onsets["time_s"]) >= 0)


def test_optimal_beats_every_seed(tabs: list[Tab]) -> None:
    best = totals(tabs, "optimal")
    for seed in SEEDS:
        other = totals(tabs, seed)
        assert best[0] > other[0], seed
        assert best[1] <= other[1], seed
        assert best[2] <= other[2], seed


def test_optimal_drops_nothing_when_two_hands_suffice(tabs: list[Tab]) -> None:
    assert totals(tabs, "optimal")[3] == 0


def test_online_at_30_ms_is_within_two_points_of_offline(tabs: list[Tab]) -> None:
    off = on = total = 0
    for tab in tabs:
        kit = load_kit(tab.kit)
        off += metrics.accuracy(optimal(tab.onsets, kit, beat_s=tab.beat_s), tab.limbs)[0]
        online = stick_online(tab.onsets, kit, 0.030, beat_s=tab.beat_s)
        m, n = metrics.accuracy(online, tab.limbs)
        on, total = on + m, total + n
    assert 100 * (off - on) / total <= 2.0


@pytest.mark.parametrize("index", range(len(TABS)))
def test_online_with_long_lookahead_equals_offline(index: int) -> None:
    tab = read_tab(TABS[index])
    kit = load_kit(tab.kit)
    off = optimal(tab.onsets, kit, beat_s=tab.beat_s)
    on = stick_online(tab.onsets, kit, 1e6, beat_s=tab.beat_s)
    np.testing.assert_array_equal(on.limb, off.limb)
    for field in on.onsets.dtype.names or ():
        np.testing.assert_array_equal(on.onsets[field], off.onsets[field])
    assert dict(on.reasons) == dict(off.reasons)


def test_online_with_long_lookahead_equals_offline_on_a_real_performance() -> None:
    perf = read_midi_file(DEMO, load_note_map("roland-td"))
    kit = load_kit("rock5")
    off = optimal(perf.onsets, kit, beat_s=perf.grid.beat_s)
    length = float(perf.onsets["time_s"][-1])
    on = stick_online(perf.onsets, kit, length + 1.0, beat_s=perf.grid.beat_s)
    np.testing.assert_array_equal(on.limb, off.limb)
    short = stick_online(perf.onsets, kit, 0.030, beat_s=perf.grid.beat_s)
    assert np.mean(short.limb == off.limb) > 0.9
