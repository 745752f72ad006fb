"""Kit animation from onsets and the window's transport state machine (pure logic)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from livedrummer.events import ONSET_DTYPE
from livedrummer.kitfile import load_kit
from livedrummer.render.animate import BEATER_REST_RAD, HIHAT_LIFT_M, kit_channels, onset_pieces
from livedrummer.render.transport import KEYS, SPEEDS, Transport
from livedrummer.scene import CH_HIGHLIGHT, CH_TRAVEL, CH_WOBBLE
from livedrummer.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Zone


def onsets(*rows: tuple[float, str, int, HiHat, float]) -> np.ndarray:
    out = np.zeros(len(rows), ONSET_DTYPE)
    for i, (t, inst, vel, hat, openness) in enumerate(rows):
        out[i]["time_s"] = t
        out[i]["instrument"] = INSTRUMENT_CODE[inst]
        out[i]["velocity"] = vel
        out[i]["zone"] = ZONES.index(Zone.HEAD)
        out[i]["hihat"] = HIHATS.index(hat)
        out[i]["openness"] = openness
    return out


KIT = load_kit("rock5")
P = {p.name: i for i, p in enumerate(KIT.pieces)}


def test_highlight_peaks_in_the_contact_frame_and_fades() -> None:
    on = onsets((1.0, "snare", 127, HiHat.NONE, np.nan))
    times = np.arange(0, 2.0, 1 / 60)
    ch = kit_channels(on, KIT, times)
    hl = ch[:, P["snare"], CH_HIGHLIGHT]
    assert np.argmax(hl) == 60 and hl[60] == pytest.approx(1.0)
    assert np.all(hl[:60] == 0)
    assert np.all(np.diff(hl[60:]) <= 0) and hl[-1] < 0.01
    others = np.delete(ch[:, :, CH_HIGHLIGHT], P["snare"], axis=1)
    assert np.all(others == 0)
    assert ch[61, P["snare"], CH_WOBBLE] > 0


def test_cymbal_swings_and_settles() -> None:
    on = onsets((0.0, "crash1", 100, HiHat.NONE, np.nan))
    w = kit_channels(on, KIT, np.arange(0, 4.0, 1 / 60))[:, P["crash1"], CH_WOBBLE]
    assert w[0] > 0.1
    assert w.min() < 0  # swings back through rest
    assert abs(w[-1]) < 0.01


def test_hihat_opening_and_kick_beater() -> None:
    on = onsets(
        (0.5, "hihat", 90, HiHat.OPEN, 1.0),
        (1.0, "hihat", 90, HiHat.CLOSED, 0.0),
        (1.5, "kick", 110, HiHat.NONE, np.nan),
    )
    times = np.array([0.2, 0.7, 1.2, 1.2, 1.5, 1.52, 2.5])
    ch = kit_channels(on, KIT, times)
    lift = ch[:, P["hihat"], CH_TRAVEL]
    assert lift[0] == 0 and lift[1] == pytest.approx(HIHAT_LIFT_M) and lift[2] == 0
    beater = ch[:, P["kick"], CH_TRAVEL]
    assert beater[0] == pytest.approx(BEATER_REST_RAD)
    assert beater[4] == 0  # at the head in the contact frame
    assert 0 < beater[5] < BEATER_REST_RAD
    assert beater[6] == pytest.approx(BEATER_REST_RAD)


def test_onsets_without_a_piece_are_ignored() -> None:
    on = onsets((0.1, "cowbell", 100, HiHat.NONE, np.nan))  # rock5 has no cowbell
    assert onset_pieces(on, KIT).tolist() == [-1]
    ch = kit_channels(on, KIT, np.array([0.1]))
    assert np.all(ch[..., CH_HIGHLIGHT] == 0)


def test_transport_plays_pauses_and_stops_at_the_end() -> None:
    tr = Transport(duration_s=10.0)
    assert tr.advance(1.0) == 0.0  # paused
    tr.apply("play_pause")
    assert tr.advance(2.5) == pytest.approx(2.5)
    tr.apply("faster")
    assert tr.speed == SPEEDS[SPEEDS.index(1.0) + 1]
    tr.advance(100.0)
    assert tr.position_s == 10.0 and not tr.playing
    tr.apply("play_pause")  # from the end: starts over
    assert tr.position_s == 0.0 and tr.playing


def test_transport_reverse_step_seek_and_markers() -> None:
    tr = Transport(duration_s=20.0, step_s=0.1)
    tr.seek(5.0)
    tr.apply("reverse")
    tr.apply("play_pause")
    assert tr.advance(1.0) == pytest.approx(4.0)
    tr.apply("step_forward")
    assert not tr.playing and tr.position_s == pytest.approx(4.1)
    tr.apply("mark")
    tr.apply("seek_forward")
    tr.apply("mark")
    tr.apply("to_start")
    tr.apply("next_mark")
    assert tr.position_s == pytest.approx(4.1)
    tr.apply("next_mark")
    assert tr.position_s == pytest.approx(9.1)
    tr.apply("previous_mark")
    assert tr.position_s == pytest.approx(4.1)
    tr.apply("previous_mark")
    assert tr.position_s == pytest.approx(4.1)  # no earlier marker: stays
    for _ in range(20):
        tr.apply("slower")
    assert tr.speed == SPEEDS[0]
    tr.apply("normal_speed")
    assert tr.speed == 1.0


def test_every_key_names_an_action() -> None:
    tr = Transport(duration_s=3.0)
    for action in set(KEYS.values()):
        tr.apply(action)
    with pytest.raises(KeyError):
        tr.apply("explode")


@given(st.lists(st.tuples(st.sampled_from(sorted(set(KEYS.values()))),
                          st.floats(0, 5)), max_size=40))  # fmt: skip
def test_transport_position_stays_in_range(steps: list[tuple[str, float]]) -> None:
    tr = Transport(duration_s=7.0)
    for action, dt in steps:
        tr.apply(action)
        tr.advance(dt)
        assert 0.0 <= tr.position_s <= 7.0
