"""The waiting hand: ready keys in a hand's rests, the ready pose over the last piece, live as
offline (:mod:`livedrummer.body.ready`)."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.body.animation import animate, hihat_openness
from livedrummer.body.perform import perform
from livedrummer.body.ready import ReadyParams, ready_keys
from livedrummer.body.rig import Rig
from livedrummer.body.skeleton import ARM
from livedrummer.body.strokes import CONTACT, TRAVEL, StrokeParams, stroke_keys
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.sticking.online import stick_online
from livedrummer.timeline.events import CONTROL_DTYPE
from livedrummer.timeline.performance import Performance
from tests.livedrummer.live.test_synth import START, TIPS, play

R = ReadyParams()


def test_ready_keys_wait_in_long_rests_only() -> None:
    t = np.array([1.0, 1.2, 2.0, 2.1])  # rests of 0.2, 0.8 and 0.1 s
    piece = np.array([0, 1, 2, 2])
    keys = stroke_keys(t, piece, np.full(4, 0.8), np.full(4, 0.5), StrokeParams(), piece)
    out = ready_keys(keys, t, R)
    assert np.all(np.diff(out.keys.time_s) >= 0)
    ready = out.keys.note >= t.size
    # one before the first note, two in the 0.8 s rest (over note 1's piece), one after the last
    np.testing.assert_array_equal(out.note, [0, 1, 1, 3])
    np.testing.assert_allclose(
        out.time_s,
        [
            1.0 - 0.05 - R.lead_s,
            1.2 + 0.05 + R.settle_s,
            2.0 - 0.05 - R.lead_s,
            2.1 + 0.05 + R.settle_s,
        ],
    )
    assert np.all(out.keys.kind[ready] == TRAVEL)
    np.testing.assert_array_equal(np.sort(out.keys.note[ready]), t.size + np.arange(4))
    # the travel arc of the rest that now waits is gone; the short rest's stays
    travel = out.keys.time_s[(out.keys.kind == TRAVEL) & ~ready]
    assert travel.size == 1 and 1.0 < travel[0] < 1.2
    assert np.count_nonzero(out.keys.kind == CONTACT) == 4
    off = ready_keys(keys, t, ReadyParams(enabled=False))
    assert off.keys is keys and off.time_s.size == 0


def test_a_resting_hand_waits_above_its_last_piece_stick_up(rig: Rig, groove: Performance) -> None:
    done = perform(groove, rig, load_note_map("roland-td"))
    st, anim = done.sticking, done.animation
    t_on = st.onsets["time_s"].astype(np.float64)
    waits = 0
    rise: list[float] = []  # the wrist above its height at the last contact
    for code, side in ((0, "R"), (1, "L")):
        notes = np.flatnonzero((st.limb == code) & (st.piece >= 0))
        t = t_on[notes]
        for i in np.flatnonzero(np.diff(t) >= R.min_gap_s):
            mid = np.linspace(t[i] + 0.05 + R.settle_s, t[i + 1] - 0.05 - R.lead_s, 5)
            if mid[-1] <= mid[0]:
                continue
            waits += 1
            n = notes[i]
            point, _, _ = rig.targets.lookup(
                st.piece[n : n + 1].astype(np.int64), st.onsets["zone"][n : n + 1].astype(np.int64)
            )
            _, wp = anim.world(mid)
            _, at = anim.world(t[i : i + 1])
            tip = wp[:, ARM[side][4]]
            across = np.linalg.norm(tip[:, :2] - point[0, :2], axis=-1)
            above = tip[:, 2] - point[0, 2]
            assert across.max() <= 0.10, f"{side} at {t[i]:.2f} s: tip {across.max():.3f} m off"
            assert 0.10 <= above.min() and above.max() <= 0.35, f"{side} at {t[i]:.2f} s"
            wrist = ARM[side][2]
            rise.append(float(wp[:, wrist, 2].min() - at[0, wrist, 2]))
    assert waits >= 20
    assert min(rise) >= 0.05 and float(np.median(rise)) >= 0.08  # up, not by the hip


def test_the_live_synth_draws_the_same_wait(rig: Rig, groove: Performance) -> None:
    """The wait is above the *last* piece, which the live synth knows: its tips in the rests are
    within 30 mm of the offline twin's (89 mm without the ready waits, the offline hand easing
    towards a note the live one has not heard yet), without prediction."""
    onsets = groove.onsets[groove.onsets["time_s"] < 7.0].copy()
    onsets["time_s"] += START
    out = play(LiveSynth(rig, SynthParams(predict=False)), onsets, 1 / 120)
    sticking = stick_online(onsets, rig.kit, 0.03)
    offline = animate(
        rig,
        sticking,
        groove.grid.beat_s + START,
        hihat_openness(onsets, np.zeros(0, CONTROL_DTYPE)),
    )
    t_on = sticking.onsets["time_s"].astype(np.float64)
    worst, waits = 0.0, 0
    for code in (0, 1):
        t = t_on[(sticking.limb == code) & (sticking.piece >= 0)]
        for i in np.flatnonzero(np.diff(t) >= R.min_gap_s):
            mid = np.linspace(t[i] + 0.05 + R.settle_s, t[i + 1] - 0.05 - R.lead_s, 4)
            _, w = offline.world(mid)
            j = np.searchsorted(out.show_s, mid + SynthParams().delay_s - 1e-9)
            live = out.rows["position"][j, TIPS[code]]
            worst = max(worst, float(np.linalg.norm(live - w[:, TIPS[code]], axis=-1).max()))
            waits += 1
    assert waits >= 4
    assert worst <= 0.030, f"live tip {worst * 1000:.1f} mm from the offline one in a wait"


@pytest.mark.parametrize("code", [0, 1])
def test_a_hand_with_nothing_to_play_waits_ready(rig: Rig, code: int) -> None:
    from livedrummer.sticking.result import Sticking
    from livedrummer.timeline.events import ONSET_DTYPE

    empty = Sticking(
        np.zeros(0, ONSET_DTYPE),
        np.zeros(0, np.int8),
        np.zeros(0, np.int16),
        {},
        "test",
        rig.kit.name,
    )
    anim = animate(
        rig,
        empty,
        np.zeros(0),
        hihat_openness(np.zeros(0, ONSET_DTYPE), np.zeros(0, CONTROL_DTYPE)),
    )
    _, wp = anim.world(np.array([0.0, 5.0]))
    side = "R" if code == 0 else "L"
    tip, wrist = wp[:, ARM[side][4]], wp[:, ARM[side][2]]
    assert np.allclose(tip[0], tip[1], atol=0.01)
    assert wrist[0, 2] > rig.skeleton.root_m[2] + 0.15  # well above the seat, not hanging
