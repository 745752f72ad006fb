"""The online synthesizer against its offline twin, prediction, idling and the pose track."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from livedrummer.body import animation
from livedrummer.body.animation import animate, hihat_openness
from livedrummer.body.ready import ReadyParams
from livedrummer.body.rig import Rig
from livedrummer.body.skeleton import J
from livedrummer.live.calibration import Calibration, CalibrationError
from livedrummer.live.predict import HandPredictor
from livedrummer.live.synth import LiveSynth, PoseBatch, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.render.body_scene import BODY_SKELETON, frame_from_pose
from livedrummer.sticking.online import stick_online
from livedrummer.timeline.events import CONTROL_DTYPE, ControlKind
from livedrummer.timeline.performance import Performance
from services.bench._upswing import upswing_visible

TIPS = {0: J["r_tip"], 1: J["l_tip"]}
START = 5000.0  # onsets live on the shared clock, far from 0


def play(synth: LiveSynth, onsets: np.ndarray, tick_s: float, tail_s: float = 0.3) -> PoseBatch:
    """Feed onsets at their times and poll like the service does; the samples as a display
    keeps them (a batch replaces what it covers: provisional samples are re-sent)."""
    now = float(onsets["time_s"][0]) - 0.2
    end = float(onsets["time_s"][-1]) + tail_s
    i, track = 0, PoseTrack(keep_s=end - now + 1.0)
    while now < end:
        while i < onsets.size and onsets["time_s"][i] <= now:
            synth.process(onsets[i])
            i += 1
        batch = synth.poses_until(now)
        if batch.show_s.size and not synth.params.provisional:
            assert track.newest_s is None or batch.show_s[0] > track.newest_s, "no sample twice"
        track.add(batch.show_s, batch.rows)
        now += tick_s
    return PoseBatch(track.show_s.copy(), track.rows.copy())


@pytest.mark.parametrize(
    ("lookahead_s", "delay_s", "provisional"),
    [(0.03, 0.03, True), (0.02, 0.05, True), (0.03, 0.03, False), (0.02, 0.05, False)],
)
def test_contacts_land_on_the_offline_contact_at_onset_plus_delay(
    rig: Rig, groove: Performance, lookahead_s: float, delay_s: float, provisional: bool
) -> None:
    onsets = groove.onsets[groove.onsets["time_s"] < 5.0].copy()
    onsets["time_s"] += START
    params = SynthParams(lookahead_s, delay_s, predict=False, provisional=provisional)
    out = play(LiveSynth(rig, params), onsets, 1 / 120)
    assert np.all(np.diff(out.show_s) > 0), "show times must increase"
    assert np.diff(out.show_s).max() <= 1 / 240 + 1e-9, "no hole in the pose stream"
    sticking = stick_online(onsets, rig.kit, lookahead_s)
    beats = groove.grid.beat_s + START
    offline = animate(rig, sticking, beats, hihat_openness(onsets, np.zeros(0, CONTROL_DTYPE)))
    hands = np.flatnonzero((sticking.limb >= 0) & (sticking.limb <= 1) & (sticking.piece >= 0))
    assert hands.size > 10
    _, world = offline.world(sticking.onsets["time_s"][hands].astype(np.float64))
    for k, i in enumerate(hands):
        show = float(sticking.onsets["time_s"][i]) + delay_s
        j = int(np.argmin(np.abs(out.show_s - show)))
        assert abs(out.show_s[j] - show) < 1e-9, f"no sample at onset {i} + D"
        tip = TIPS[int(sticking.limb[i])]
        miss = np.linalg.norm(out.rows["position"][j, tip] - world[k, tip])
        assert miss < 0.003, f"onset {i}: live tip {miss * 1000:.1f} mm from the offline contact"


def test_delay_shorter_than_lookahead_is_refused() -> None:
    with pytest.raises(ValueError, match="lookahead"):
        SynthParams(lookahead_s=0.05, delay_s=0.03)


def test_with_no_input_the_drummer_breathes(rig: Rig) -> None:
    synth = LiveSynth(rig)
    shows, heads = [], []
    for k in range(6 * 30):
        batch = synth.poses_until(START + k / 30)
        shows.append(batch.show_s)
        heads.append(batch.rows["position"][:, J["head"]])
    show = np.concatenate(shows)
    head = np.concatenate(heads)
    assert np.diff(show).max() <= 1 / 240 + 1e-9
    assert np.ptp(head[:, 1]) > 0.002, "the head should sway (never freeze)"
    assert np.abs(np.diff(head, axis=0)).max() < 0.002, "idling is smooth"


def test_prediction_raises_the_stick_before_regular_hits(
    rig: Rig, groove: Performance, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a hand resting long enough waits ready (livedrummer.body.ready), its stick up live as
    # offline, which leaves the predictor nothing to add on this groove (0.97 either way, see
    # test_body_ready): its own share is measured without the ready waits
    monkeypatch.setattr(animation, "READY", ReadyParams(enabled=False))
    onsets = groove.onsets[groove.onsets["time_s"] < 7.0].copy()
    onsets["time_s"] += START
    prep = 0.05
    figures = {}
    for predict in (False, True):
        synth = LiveSynth(rig, SynthParams(predict=predict))
        out = play(synth, onsets, 1 / 120)
        sticking = stick_online(onsets, rig.kit, 0.03)
        offline = animate(
            rig,
            sticking,
            groove.grid.beat_s + START,
            hihat_openness(onsets, np.zeros(0, CONTROL_DTYPE)),
        )
        hands = np.flatnonzero((sticking.limb >= 0) & (sticking.limb <= 1) & (sticking.piece >= 0))
        t = sticking.onsets["time_s"][hands].astype(np.float64)
        _, at = offline.world(t)
        _, before = offline.world(t - prep)
        tip = np.array([TIPS[int(sticking.limb[i])] for i in hands])
        j = np.searchsorted(out.show_s, t - prep + 0.03 - 1e-9)
        live = out.rows["position"][j, tip, 2]
        u = upswing_visible(before[np.arange(t.size), tip, 2], at[np.arange(t.size), tip, 2], live)
        figures[predict] = u.fraction
        assert u.notes > 10
    assert figures[True] > figures[False]


def test_hand_predictor_follows_a_pulse_and_gives_up_on_rests() -> None:
    pred = HandPredictor()
    assert pred.guess(0, 0.0) is None
    for k in range(4):
        pred.observe(10.0 + 0.25 * k, 0, 2, 0, 90)
    guess = pred.guess(0, 10.75)
    assert guess is not None and guess.time_s == pytest.approx(11.0) and guess.piece == 2
    missed = pred.guess(0, 11.0)
    assert missed is not None and missed.time_s == pytest.approx(11.25)
    assert pred.guess(0, 12.0) is None  # three expectations missed: no rhythm any more
    assert pred.guess(1, 10.0) is None  # the other hand has no history
    pred.observe(20.0, 0, 2, 0, 90)  # after a long rest the history starts again
    assert pred.guess(0, 20.0) is None


def test_upswing_measure_counts_only_notes_with_a_preparation() -> None:
    u = upswing_visible(
        offline_prep_z=np.array([1.10, 1.10, 1.01, 1.20]),
        offline_contact_z=np.array([1.00, 1.00, 1.00, 1.00]),
        live_prep_z=np.array([1.06, 1.04, 1.00, 1.20]),
    )
    assert (u.notes, u.visible) == (3, 2)


def test_pose_track_holds_the_last_pose_and_resumes(rig: Rig) -> None:
    synth = LiveSynth(rig)
    first = synth.poses_until(START)
    track = PoseTrack(keep_s=1.0)
    assert track.at(START) is None
    track.add(first.show_s, first.rows)
    newest = track.newest_s
    assert newest is not None
    got = track.at(newest + 10.0)  # the stream stopped: hold the last pose
    assert got is not None and got[0] == newest
    later = synth.poses_until(START + 0.5)
    track.add(later.show_s, later.rows)
    got = track.at(float(later.show_s[-1]))
    assert got is not None and got[0] == later.show_s[-1]
    frame = frame_from_pose(got[1], got[0], rig.kit)
    frame.check(BODY_SKELETON, len(rig.kit.pieces))


def test_calibration_round_trip_and_strict_keys(tmp_path: Path) -> None:
    path = tmp_path / "calibration.toml"
    assert Calibration.load(path) == Calibration()
    cal = Calibration(input_ms=-3.5, audio_ms=12.0, display_ms=40.0)
    cal.save(path)
    assert Calibration.load(path) == cal
    path.write_text("input_ms = 1.0\nvideo_ms = 3.0\n")
    with pytest.raises(CalibrationError, match="video_ms"):
        Calibration.load(path)
    path.write_text("audio_ms = 900.0\n")
    with pytest.raises(CalibrationError, match="audio_ms"):
        Calibration.load(path)


def test_next_due_is_when_a_hand_note_gets_committed(rig: Rig, groove: Performance) -> None:
    params = SynthParams()
    synth = LiveSynth(rig, params)
    onsets = groove.onsets.copy()
    onsets["time_s"] += START
    snare = onsets[onsets["instrument"] == 1][0]
    t = float(snare["time_s"])
    synth.poses_until(t - 0.1)
    assert synth.next_due_s(t - 0.1) is None
    synth.process(snare)
    assert synth.next_due_s(t - 0.1) == pytest.approx(t + params.lookahead_s)
    synth.poses_until(t + params.lookahead_s)
    assert synth.next_due_s(t) is None


@pytest.mark.parametrize("provisional", [True, False])
def test_a_hit_s_contact_goes_out_on_arrival_only_when_provisional(
    rig: Rig, groove: Performance, provisional: bool
) -> None:
    params = SynthParams(provisional=provisional)
    synth = LiveSynth(rig, params)
    onsets = groove.onsets[groove.onsets["time_s"] < 4.0].copy()
    onsets["time_s"] += START
    now = float(onsets["time_s"][0]) - 0.2
    synth.poses_until(now)
    sticking = stick_online(onsets, rig.kit, params.lookahead_s)
    is_hand = (sticking.limb >= 0) & (sticking.limb <= 1) & (sticking.piece >= 0)
    on_arrival, hands = 0, 0
    for k, row in enumerate(sticking.onsets):
        t = float(row["time_s"])
        while now + 1 / 120 < t:  # the service's ticks between notes
            now += 1 / 120
            synth.poses_until(now)
        now = t + 0.0005  # the note arrives, the service publishes at once
        synth.process(row)
        batch = synth.poses_until(now)
        if not is_hand[k]:
            continue
        hands += 1
        on_arrival += bool(np.any(np.abs(batch.show_s - (t + params.delay_s)) < 1e-9))
    assert hands > 10
    if provisional:
        assert on_arrival == hands, "every hand hit's contact is published when it arrives"
    else:
        assert on_arrival == 0, "without provisional poses a contact waits for its decision"


def _target(rig: Rig, row: np.void | np.ndarray, limb: int, piece: int) -> np.ndarray:
    if limb >= 2:
        p = rig.kit.pieces[piece]
        return np.asarray(p.pedal_position_m or p.position_m, dtype=np.float64)
    point, _, _ = rig.targets.lookup(
        np.array([piece]), np.array([int(row["zone"])]), np.array([float(row["openness"])])
    )
    out: np.ndarray = point[0]
    return out


ENDS = {0: J["r_tip"], 1: J["l_tip"], 2: J["r_toe"], 3: J["l_toe"]}


def test_every_hit_gets_its_contact_on_arrival_on_its_target(rig: Rig, groove: Performance) -> None:
    params = SynthParams()
    synth = LiveSynth(rig, params)
    onsets = groove.onsets[groove.onsets["time_s"] < 8.0].copy()
    onsets["time_s"] += START
    sticking = stick_online(onsets, rig.kit, params.lookahead_s)
    now = float(onsets["time_s"][0]) - 0.2
    track = PoseTrack(keep_s=20.0)
    quick: dict[float, np.ndarray] = {}
    for row in sticking.onsets:
        t = float(row["time_s"])
        while now + 1 / 120 < t:
            now += 1 / 120
            b = synth.poses_until(now)
            track.add(b.show_s, b.rows)
        now = t + 0.0005
        synth.process(row)
        q = synth.take_quick()  # what the service sends before re-animating
        track.add(q.show_s, q.rows)
        assert q.show_s[-1] == pytest.approx(t + params.delay_s, abs=1e-9)
        assert np.diff(track.show_s).max() <= 1 / 240 + 1e-9, "no hole before the hit"
        quick[float(q.show_s[-1])] = q.rows[-1]
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
    for _ in range(60):
        now += 1 / 120
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
    played = np.flatnonzero((sticking.limb >= 0) & (sticking.piece >= 0))
    assert synth.quick_contacts == onsets.size and played.size > 40
    same_hand = hands = 0
    for i in played:
        row, limb, piece = sticking.onsets[i], int(sticking.limb[i]), int(sticking.piece[i])
        show = float(row["time_s"]) + params.delay_s
        target = _target(rig, row, limb, piece)
        pos = quick[show]["position"].astype(np.float64)
        ends = (0, 1) if limb < 2 else (limb,)  # its hand may be provisional, not its piece
        gap = {k: float(np.linalg.norm(pos[ENDS[k]] - target)) for k in ends}
        assert min(gap.values()) < 1e-3, f"note {i}: quick contact {min(gap.values())} m off"
        if limb < 2:
            hands += 1
            same_hand += min(gap, key=lambda k: gap[k]) == limb
        j = int(np.argmin(np.abs(track.show_s - show)))
        assert abs(track.show_s[j] - show) < 1e-9, "the contact sample stays on the track"
        final = track.rows["position"][j, ENDS[limb]].astype(np.float64)
        assert np.linalg.norm(final - target) < 1e-3, f"note {i}: final contact off target"
    assert same_hand >= 0.95 * hands, f"provisional hand right for {same_hand} of {hands}"


def test_a_hit_during_a_re_animation_is_answered_and_kept(rig: Rig, groove: Performance) -> None:
    params = SynthParams()
    synth = LiveSynth(rig, params)
    onsets = groove.onsets[groove.onsets["time_s"] < 4.0].copy()
    onsets["time_s"] += START
    k = onsets.size // 2
    while onsets["time_s"][k + 1] - onsets["time_s"][k] < 0.02:  # two hits apart
        k += 1
    now = float(onsets["time_s"][0]) - 0.2
    for row in onsets[: k + 1]:
        while now + 1 / 120 < float(row["time_s"]):
            now += 1 / 120
            synth.poses_until(now)
        synth.process(row)
        synth.take_quick()
    late = onsets[k + 1]
    answered: list[PoseBatch] = []

    def answer() -> None:  # what the service does between the steps
        if not answered:
            synth.process(late)
            answered.append(synth.take_quick())

    calls = 0

    def pause() -> None:
        nonlocal calls
        calls += 1
        answer()

    before = synth.animations
    batch = synth.poses_until(float(late["time_s"]) + 0.0005, answer=pause)
    assert synth.animations == before + 1 and calls >= 5, calls
    show = float(late["time_s"]) + params.delay_s
    assert answered and answered[0].show_s[-1] == pytest.approx(show, abs=1e-9)
    # the batch came from curves built without the late hit: it still carries its contact
    j = np.flatnonzero(np.abs(batch.show_s - show) < 1e-9)
    assert j.size == 1
    # bit-exact by design: the quick answer is a copy of the sample the curves hold
    assert np.array_equal(batch.rows["position"][j[0]], answered[0].rows["position"][-1])
    again = synth.poses_until(float(late["time_s"]) + 0.004)
    assert synth.animations == before + 2, "the late hit joins the curves at the next call"
    assert np.any(np.abs(again.show_s - show) < 1e-9)


def test_the_clearance_memo_gives_the_same_curves_without_searching_again(
    rig: Rig, groove: Performance, monkeypatch: pytest.MonkeyPatch
) -> None:
    import livedrummer.body.animation as animation

    on = groove.onsets[groove.onsets["time_s"] < 6.0]
    st = stick_online(on, rig.kit, 0.03)
    beats = groove.grid.beat_s
    openness = hihat_openness(on, groove.controls[:0])
    searched: list[int] = []
    search = animation._search

    def counting(*args, **kwargs):  # type: ignore[no-untyped-def]
        searched.append(int(args[3].size))
        return search(*args, **kwargs)

    monkeypatch.setattr(animation, "_search", counting)
    memo: animation.ClearanceMemo = {}
    fresh = animate(rig, st, beats, openness)
    first = sum(searched)
    assert first > 0, "this groove has keys whose arcs dip into the kit"
    animate(rig, st, beats, openness, memo=memo)
    assert memo, "the search's settings are remembered"
    searched.clear()
    again = animate(rig, st, beats, openness, memo=memo)
    assert sum(searched) == 0, "a window seen before is not searched again"
    t = np.linspace(float(on["time_s"][0]), float(on["time_s"][-1]), 400)
    for a, b in zip(fresh.world(t), again.world(t), strict=True):
        assert np.allclose(a, b, atol=1e-9)


def test_a_moving_pedal_alone_re_animates_at_most_every_control_period(rig: Rig) -> None:
    params = SynthParams()
    synth = LiveSynth(rig, params)
    now = START
    synth.poses_until(now)
    before = synth.animations
    seconds, rate = 1.0, 200  # CC4 at 200 messages/s, no notes
    for k in range(int(seconds * rate)):
        now = START + k / rate
        row = np.zeros((), CONTROL_DTYPE)
        row["time_s"], row["kind"], row["number"] = now, ControlKind.HIHAT_PEDAL, 4
        row["value"] = k % 128
        synth.control(row)
        synth.poses_until(now)
    runs = synth.animations - before
    assert 2 <= runs <= seconds / params.control_every_s + 3, runs


def _idling(
    rig: Rig, groove: Performance, params: SynthParams
) -> tuple[LiveSynth, np.ndarray, float, PoseTrack]:
    """A synth that has published a quarter second of poses into a track, no hit yet; the
    groove's first 3 s of onsets on the shared clock; the clock's now."""
    synth = LiveSynth(rig, params)
    onsets = groove.onsets[groove.onsets["time_s"] < 3.0].copy()
    onsets["time_s"] += START
    now = float(onsets["time_s"][0]) - 0.2
    track = PoseTrack(keep_s=20.0)
    for _ in range(30):
        now += 1 / 120
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
    return synth, onsets, now, track


def test_a_burst_s_contacts_go_out_together_without_hiding_the_samples_between(
    rig: Rig, groove: Performance
) -> None:
    params = SynthParams()
    synth, onsets, now, track = _idling(rig, groove, params)
    # three hits that arrived in one message (a flam, then a hit 36 ms later)
    burst = onsets[:3].copy()
    burst["time_s"] = now - np.array([0.040, 0.038, 0.002])
    synth.process(burst)
    quick = synth.take_quick()
    contacts = list(burst["time_s"] + params.delay_s)
    assert np.isin(np.round(contacts, 9), np.round(quick.show_s, 9)).all()
    assert quick.show_s[0] == pytest.approx(contacts[0]) and np.all(np.diff(quick.show_s) > 0)
    held = track.show_s[(track.show_s > contacts[0]) & (track.show_s < contacts[-1])].copy()
    assert held.size >= 2
    track.add(quick.show_s, quick.rows)
    assert np.isin(held, track.show_s).all(), "the contacts' batch hid the samples between"


def test_a_later_contacts_batch_keeps_the_earlier_contacts_it_covers(
    rig: Rig, groove: Performance
) -> None:
    params = SynthParams()
    synth, onsets, now, track = _idling(rig, groove, params)
    # hits read one after another after the last tick, while the synth is busy (no tick
    # between them): each batch covers the range from what was published to its hit
    hits = onsets[:4].copy()
    hits["time_s"] = now + np.array([0.001, 0.002, 0.003, 0.006])
    for hit in hits:
        synth.process(hit)
        q = synth.take_quick()
        track.add(q.show_s, q.rows)
    for hit in hits:
        show = float(hit["time_s"]) + params.delay_s
        assert np.any(np.abs(track.show_s - show) < 1e-9), f"the contact at {show} was erased"


def test_a_quick_contact_leaves_the_synth_as_it_was(rig: Rig, groove: Performance) -> None:
    from livedrummer.live.quick import quick_contact

    params = SynthParams()
    synth = LiveSynth(rig, params)
    onsets = groove.onsets[groove.onsets["time_s"] < 6.0].copy()
    onsets["time_s"] += START
    sticking = stick_online(onsets, rig.kit, params.lookahead_s)
    now = float(onsets["time_s"][0]) - 0.2
    answered = 0
    for row, limb, piece in zip(sticking.onsets, sticking.limb, sticking.piece, strict=True):
        t = float(row["time_s"])
        while now + 1 / 120 < t:
            now += 1 / 120
            synth.poses_until(now)
        state = synth.quick_state()
        before = (state.samples_t.copy(), state.samples.copy(), dict(state.struck))
        shows, rows = quick_contact(state, row, int(limb), int(piece))
        assert np.array_equal(state.samples_t, before[0])
        assert np.array_equal(state.samples, before[1])
        assert state.struck.keys() == before[2].keys()
        if shows.size:
            answered += 1
            assert shows.tolist() == [t] and rows.size == 1
        now = t + 0.0005
        synth.process(row, quick=False)
        synth.poses_until(now)
    assert answered > 5


def test_a_batch_replaces_exactly_the_range_it_covers() -> None:
    dtype = np.dtype([("time_s", "<f4"), ("v", "<i4")])

    def batch(times: list[float], v: int) -> tuple[np.ndarray, np.ndarray]:
        rows = np.zeros(len(times), dtype)
        rows["v"] = v
        return np.array(times), rows

    track = PoseTrack(keep_s=100.0)
    track.add(*batch([1.0, 2.0, 3.0, 4.0], 1))
    track.add(*batch([6.0, 7.0], 3))  # sent ahead (a quick contact)
    track.add(*batch([2.5, 3.0, 3.5, 5.0], 2))  # a re-sent range
    assert track.show_s.tolist() == [1.0, 2.0, 2.5, 3.0, 3.5, 5.0, 6.0, 7.0]
    assert track.rows["v"].tolist() == [1, 1, 2, 2, 2, 2, 3, 3]
    assert track.at(6.5) is not None and int(track.at(6.5)[1]["v"]) == 3  # type: ignore[index]
