"""The live score and angle models against their file twins on the same onsets and poses."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.body.skeleton import J
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import INSTRUMENTS
from livedrummer.render.live_overlay import LiveAngles, LiveScore, LiveStrips
from livedrummer.render.overlay import AngleModel, ScoreModel
from livedrummer.sticking.prepare import route
from livedrummer.sticking.result import Sticking
from livedrummer.timeline.events import ONSET_DTYPE


@pytest.fixture(scope="module")
def kit() -> Kit:
    return load_kit("rock5")


def onsets(n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    out = np.zeros(n, ONSET_DTYPE)
    out["time_s"] = 100.0 + np.cumsum(rng.uniform(0.02, 0.3, n))
    out["velocity"] = rng.integers(1, 128, n)
    out["instrument"] = rng.integers(0, len(INSTRUMENTS), n)
    out["zone"] = rng.integers(0, 3, n)
    return out


@pytest.mark.parametrize("grouped", [False, True])
def test_the_live_score_shows_what_the_file_score_shows_of_the_onsets_received(
    kit: Kit, grouped: bool
) -> None:
    notes = onsets(200)
    routed = route(notes, kit)
    file = ScoreModel.from_sticking(
        Sticking(notes, routed.limb, routed.piece, {}, "test", kit.name), kit, grouped
    )
    live = LiveScore(kit, grouped)
    compared = 0
    for chunk in np.array_split(notes, 40):  # as the synth forwards them, a few at a time
        live.add(chunk)
        received = float(chunk["time_s"][-1])
        for now in (received - 0.3, received - 3.0):
            got, want = live.view(now), file.view(now)
            arrived = file.time_s[(file.time_s >= now - 4.0) & (file.time_s <= now + 4.0)]
            keep = arrived <= received
            np.testing.assert_allclose(got.x, want.x[keep])
            np.testing.assert_array_equal(got.lane, want.lane[keep])
            np.testing.assert_array_equal(got.velocity, want.velocity[keep])
            np.testing.assert_array_equal(got.limb, want.limb[keep])
            compared += got.x.size
    assert compared > 500
    assert live.unplaced == file.unplaced > 0
    assert live.time_s[0] > notes["time_s"][-1] - 10.0  # old onsets are forgotten


def test_live_angles_resample_received_poses_as_the_file_graph_samples_them() -> None:
    rng = np.random.default_rng(5)
    rate = 60.0
    n = 600  # 10 s
    joints = np.cumsum(rng.normal(0.0, 0.01, (n, 24, 3)), axis=0) + rng.normal(0, 0.3, (24, 3))
    file = AngleModel.from_joints(joints, rate)
    live = LiveAngles(rate, keep_s=60.0)
    times = np.arange(n) / rate
    start = 0
    while start < n:  # messages of 12 samples, each resending the 4 before it (re-animation)
        lo = max(start - 4, 0)
        stale = joints[lo : start + 12] + (0.05 if start else 0.0)  # resent samples differ
        live.add(times[lo : start + 12], stale)
        live.add(times[lo : start + 12], joints[lo : start + 12])
        start += 12
    for now in (4.5, 6.0, 5.01):
        got, want = live.view(now), file.view(now)
        np.testing.assert_allclose(got.x, want.x)
        np.testing.assert_allclose(got.degrees, want.degrees, atol=1e-3)
    assert live.view(100.0).x.size == 0  # nothing received there
    early = live.view(1.0)  # the graph starts at the first pose received
    assert early.x.size == int(5.0 * rate) + 1
    short = LiveAngles(rate)  # the default keeps the strip's history, not the whole show
    short.add(times, joints)
    assert short.time_s[0] == pytest.approx(times[-1] - 9.0, abs=1.0 / rate)
    np.testing.assert_allclose(short.view(8.0).degrees, file.view(8.0).degrees, atol=1e-3)


def test_strips_image_follows_the_feed(kit: Kit) -> None:
    strips = LiveStrips(kit)
    img = strips.image((320, 240), frozenset({"score", "joints"}))
    empty = img.paint(101.0).copy()
    strips.add_onsets(onsets(30))
    full = img.paint(101.0)
    assert img is strips.image((320, 240), frozenset({"score", "joints"}))
    assert np.count_nonzero(np.any(full != empty, axis=-1)) > 50


def test_the_poses_tell_which_hand_played_a_note(kit: Kit) -> None:
    """Right stick on the ride, left on the snare: the ride's notes turn right-hand, the
    snare's left-hand, once poses cover them; a note no pose covers stays grey."""
    names = [p.name for p in kit.pieces]
    ride = next(i for i, p in enumerate(kit.pieces) if p.kind.name == "RIDE")
    snare = next(i for i, p in enumerate(kit.pieces) if p.kind.name == "SNARE")
    code = {n: i for i, n in enumerate(INSTRUMENTS)}
    ride_code = next(c for n, c in code.items() if kit.resolve(n) is kit.pieces[ride])
    snare_code = next(c for n, c in code.items() if kit.resolve(n) is kit.pieces[snare])
    notes = np.zeros(3, ONSET_DTYPE)
    notes["time_s"] = [10.0, 10.1, 12.0]
    notes["instrument"] = [ride_code, snare_code, snare_code]
    notes["velocity"] = 100
    strips = LiveStrips(kit)
    strips.add_onsets(notes)
    score = strips.scores[False]
    assert (score.limb == -1).all(), names
    joints = np.zeros((30, 24, 3))
    joints[:, J["r_tip"]] = kit.pieces[ride].position_m
    joints[:, J["l_tip"]] = kit.pieces[snare].position_m
    strips.add_poses(9.5 + np.arange(30) / 30.0, joints)  # covers 9.5 .. 10.47
    for s in strips.scores.values():
        np.testing.assert_array_equal(s.limb, [0, 1, -1])
