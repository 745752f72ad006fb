"""The text score and the drum tab: written, edited by hand, read back, honoured."""

from __future__ import annotations

import numpy as np
import pytest
from test_sticking_helpers import DEMO, onsets

from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.prepare import UNANNOTATED
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED
from livedrummer.sticking.score import read_score, write_score
from livedrummer.sticking.sheet import render_sheet
from livedrummer.sticking.strategy import STRATEGIES, assign
from livedrummer.sticking.tab import ScoreError, parse_tab

RH, LH, LF = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH], LIMB_CODE[Limb.LF]


@pytest.fixture(scope="module")
def perf():  # type: ignore[no-untyped-def]
    return read_midi_file(DEMO, load_note_map("roland-td"))


def test_written_score_reads_back_as_the_same_limbs(perf) -> None:  # type: ignore[no-untyped-def]
    kit = load_kit("rock5")
    result = assign(perf.onsets, kit, beat_s=perf.grid.beat_s)
    explicit = read_score(write_score(result, kit, "roland-td"), perf.onsets)
    np.testing.assert_array_equal(explicit, result.limb)


@pytest.mark.parametrize("strategy", list(STRATEGIES))
def test_hand_edits_win_over_every_strategy(perf, strategy: str) -> None:  # type: ignore[no-untyped-def]
    kit = load_kit("rock5")
    result = assign(perf.onsets, kit, strategy, beat_s=perf.grid.beat_s)
    lines = write_score(result, kit).splitlines()
    hats = [k for k, line in enumerate(lines) if " hihat " in line and " RH" in line][:5]
    for k in hats:
        lines[k] = lines[k].replace(" RH", " LH")
    snare = next(k for k, line in enumerate(lines) if " snare " in line)
    lines[snare] = lines[snare].replace(" LH", " -").replace(" RH", " -")
    explicit = read_score("\n".join(lines), perf.onsets)
    edited = assign(perf.onsets, kit, strategy, beat_s=perf.grid.beat_s, explicit=explicit)
    marked = explicit != UNANNOTATED
    np.testing.assert_array_equal(edited.limb[marked], explicit[marked])
    assert np.count_nonzero(edited.limb == NOT_PLAYED) >= 1
    assert any("score" in r for r in edited.reasons.values())


def test_open_notes_are_left_to_the_strategy_and_fitted_around_the_marked_ones() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "snare"), (0.1, "snare"), (0.2, "snare"), (0.3, "snare"))
    text = "0.0 0 snare LH\n0.1 0 snare ?\n0.2 0 snare ?\n0.3 0 snare ?\n"
    explicit = read_score(text, on)
    assert explicit.tolist() == [LH, UNANNOTATED, UNANNOTATED, UNANNOTATED]
    assert assign(on, kit, explicit=explicit).limb.tolist() == [LH, RH, LH, RH]


def test_a_foot_on_a_hihat_note_moves_it_to_the_pedal() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "hihat"), (0.0, "snare"))
    explicit = read_score("0 0 hihat LF\n0 0 snare ?\n", on)
    result = assign(on, kit, explicit=explicit)
    assert result.limb.tolist()[0] == LF and "pedal" in result.reasons[0]


def test_bad_scores_name_the_line(perf) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ScoreError, match=r":2: limb 'XX'"):
        read_score("# c\n0.0 38 snare XX\n", perf.onsets)
    with pytest.raises(ScoreError, match=r":1: no note 38 at 999"):
        read_score("999.0 38 snare RH\n", perf.onsets)
    with pytest.raises(ScoreError, match=":1: expected"):
        read_score("0.0 38\n", perf.onsets)


def test_tab_parses_cells_ghosts_and_errors() -> None:
    tab = parse_tab("tempo 60\nsteps 2\nhihat R r | R .\nsnare . L | X .\nkick RF . | . .\n")
    assert tab.onsets["time_s"].tolist() == [0.0, 0.0, 0.5, 0.5, 1.0, 1.0]
    assert tab.onsets["velocity"].tolist()[2] == 40  # the ghost
    assert NOT_PLAYED in tab.limbs.tolist()
    with pytest.raises(ScoreError, match="cells"):
        parse_tab("hihat R R\nsnare L\n")
    with pytest.raises(ScoreError, match="unknown instrument"):
        parse_tab("bongo R\n")
    with pytest.raises(ScoreError, match="cell 1"):
        parse_tab("snare Q\n")


def test_sheet_shows_bars_beats_and_limbs(perf) -> None:  # type: ignore[no-untyped-def]
    kit = load_kit("rock5")
    result = assign(perf.onsets, kit, beat_s=perf.grid.beat_s)
    text = render_sheet(result, kit, perf.grid.beat_s, perf.grid.bar, perf.grid.beat_in_bar)
    assert "bar 2" in text
    assert "hihat R" in text and "snare L" in text and "kick RF" in text
