"""The online form: commit timing, chords arriving after a commit, and its guard rails."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_sticking_helpers import DEMO, onsets

from livedrummer.kit.loader import load_kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.online import OnlineSticker, stick_online
from livedrummer.sticking.optimal import optimal
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED

RH, LH = LIMB_CODE[Limb.RH], LIMB_CODE[Limb.LH]


@pytest.mark.parametrize("lookahead", [0.0, 0.03, 0.2])
def test_every_note_is_decided_within_the_lookahead_of_stream_time(lookahead: float) -> None:
    perf = read_midi_file(DEMO, load_note_map("roland-td"))
    sticker = OnlineSticker(load_kit("rock5"), lookahead)
    decided: set[int] = set()
    times = perf.onsets["time_s"]
    for k, row in enumerate(perf.onsets):
        decided.update(d.index for d in sticker.process(row))
        due = np.flatnonzero(times[: k + 1] + lookahead <= times[k])
        assert set(due.tolist()) <= decided
    decided.update(d.index for d in sticker.flush())
    assert decided == set(range(perf.onsets.size))


def test_advance_commits_on_the_clock_without_new_notes() -> None:
    sticker = OnlineSticker(load_kit("rock5"), 0.05)
    row = onsets((1.0, "snare"))[0]
    assert sticker.process(row) == []
    assert sticker.advance(1.02) == []
    (decision,) = sticker.advance(1.05)
    assert decision.index == 0 and decision.limb in (RH, LH)


def test_a_chord_mate_after_a_zero_lookahead_commit_takes_the_other_hand() -> None:
    sticker = OnlineSticker(load_kit("rock5"), 0.0)
    on = onsets((0.0, "hihat"), (0.005, "snare"), (0.008, "crash2"))
    first = sticker.process(on[0])
    second = sticker.process(on[1])
    third = sticker.process(on[2])
    assert len(first) == len(second) == len(third) == 1
    assert {first[0].limb, second[0].limb} == {RH, LH}
    # no third hand: the crash merges into the nearer stroke (the snare's), a flam of its hand
    assert third[0].limb == second[0].limb and third[0].reason is not None
    assert third[0].reason.startswith("merged")


def test_a_pending_note_s_provisional_limb_is_almost_always_its_decision() -> None:
    perf = read_midi_file(DEMO, load_note_map("roland-td"))
    sticker = OnlineSticker(load_kit("rock5"), 0.03)
    said: dict[int, tuple[int, int]] = {}
    final: dict[int, tuple[int, int]] = {}
    for k, row in enumerate(perf.onsets):
        for d in sticker.process(row):
            final[d.index] = (d.limb, d.piece)
        if k not in final:  # pending: what the cheapest path so far gives it
            said[k] = sticker.provisional(k)
    for d in sticker.flush():
        final[d.index] = (d.limb, d.piece)
    assert len(said) > 100
    same = sum(said[k] == final[k] for k in said)
    assert same >= 0.97 * len(said), f"{same} of {len(said)}"
    decided = next(iter(final))
    assert sticker.provisional(decided) == final[decided], "a decided note keeps its decision"
    assert sticker.provisional(perf.onsets.size) == (NOT_PLAYED, -1), "an index not seen"


def test_reset_forgets_the_past() -> None:
    kit = load_kit("rock5")
    on = onsets((0.0, "snare"), (0.1, "snare"), (0.2, "tom1"))
    sticker = OnlineSticker(kit, 0.0)
    first = [d.limb for row in on for d in sticker.process(row)]
    sticker.reset()
    again = [d.limb for row in on for d in sticker.process(row)]
    assert first == again


def test_zero_lookahead_still_plays_everything_two_hands_can() -> None:
    perf = read_midi_file(DEMO, load_note_map("roland-td"))
    result = stick_online(perf.onsets, load_kit("rock5"), 0.0)
    assert np.count_nonzero(result.limb == NOT_PLAYED) == 0


def test_negative_lookahead_is_refused() -> None:
    with pytest.raises(ValueError, match="lookahead"):
        OnlineSticker(load_kit("rock5"), -0.01)


def test_committed_steps_are_forgotten_so_a_long_show_stays_small() -> None:
    perf = read_midi_file(DEMO, load_note_map("roland-td"))
    sticker = OnlineSticker(load_kit("rock5"), 0.03)
    for row in perf.onsets:
        sticker.process(row)
        assert len(sticker._trellis.backpointers) <= 4


instruments = st.sampled_from(
    ["snare", "hihat", "tom1", "tom3", "crash1", "crash2", "ride", "kick", "hihat:pedal"]
)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 60), instruments), min_size=1, max_size=50))
def test_online_equals_offline_when_it_can_see_everything(notes: list[tuple[int, str]]) -> None:
    kit = load_kit("rock5")
    on = onsets(*[(0.007 * t, name) for t, name in notes])
    off = optimal(on, kit)
    online = stick_online(on, kit, 10.0)
    np.testing.assert_array_equal(online.limb, off.limb)
    assert dict(online.reasons) == dict(off.reasons)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.integers(0, 60), instruments), min_size=1, max_size=50),
    st.sampled_from([0.0, 0.004, 0.03]),
)
def test_short_lookahead_decides_every_note_once(notes: list[tuple[int, str]], la: float) -> None:
    on = onsets(*[(0.007 * t, name) for t, name in notes])
    sticker = OnlineSticker(load_kit("rock5"), la)
    seen = [d.index for row in on for d in sticker.process(row)] + [
        d.index for d in sticker.flush()
    ]
    assert sorted(seen) == list(range(on.size))
