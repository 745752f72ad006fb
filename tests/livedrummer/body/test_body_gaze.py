"""Where the drummer looks (:mod:`livedrummer.body.gaze`): towards the struck piece, smoothed,
limited, with the eyes making up what the head leaves."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from livedrummer.body import quat
from livedrummer.body.gaze import GazeParams, azimuth, eye_angles, gaze_direction, gaze_keys
from livedrummer.body.perform import perform
from livedrummer.body.rig import Rig
from livedrummer.body.secondary import SecondaryParams
from livedrummer.body.skeleton import J
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file

P = GazeParams()
FILES = ("drummer6/session1/1_rock_70_beat_6-8.mid", "drummer1/session1/102_funk_95_beat_4-4.mid")


def test_alternating_hits_hold_the_gaze_between_them_and_a_lone_hit_takes_it() -> None:
    t = np.arange(16) * 0.0625  # sixteenths at 120 bpm
    left, right = np.array([-0.3, 0.5, -0.3]), np.array([0.3, 0.5, -0.3])
    rel = np.where((np.arange(16) % 2 == 0)[:, None], left, right)
    yaw, _ = gaze_keys(t, rel, P)
    raw = azimuth(rel)
    assert np.ptp(yaw[4:]) < 0.45 * np.ptp(raw)  # settles between them, not at each in turn
    assert abs(yaw[4:].mean()) < np.radians(5.0)
    # a crash far to the right after half a second of rest: nearly all the way, within a key
    t2 = np.array([0.0, 0.5])
    rel2 = np.array([left, [0.9, 0.4, 0.2]])
    yaw2, pitch2 = gaze_keys(t2, rel2, P)
    assert abs(yaw2[1] - azimuth(rel2[1])) < 0.05 * abs(azimuth(rel2[1]) - azimuth(rel2[0]))
    assert pitch2[1] > 0.0  # looking up at it


def test_the_gaze_is_limited_in_angle_and_speed() -> None:
    t = np.array([0.0, 0.05, 1.0])
    rel = np.array([[0.0, 1.0, 0.0], [-1.0, -0.2, -3.0], [-1.0, -0.2, -3.0]])  # behind, below
    yaw, pitch = gaze_keys(t, rel, P)
    assert np.all(np.abs(yaw) <= np.radians(P.yaw_max_deg) + 1e-12)
    assert np.all(pitch >= np.radians(P.pitch_deg[0]) - 1e-12)
    assert np.all(np.abs(np.diff(yaw)) <= np.radians(P.speed_deg_s) * np.diff(t) + 1e-12)


def test_the_eyes_make_up_the_heads_share_within_their_limit() -> None:
    f = SecondaryParams().look_fraction
    for deg in (10.0, 30.0, 60.0):
        head = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians([f * deg]))
        yaw, pitch = eye_angles(head, f, 0.0, P)
        want = min((1.0 - f) * deg, P.eye_max_deg)
        assert np.degrees(yaw[0]) == pytest.approx(want, abs=1e-6)
        assert pitch[0] == pytest.approx(0.0, abs=1e-9)
        g = gaze_direction(head, f, 0.0, P)
        assert np.degrees(azimuth(g[0])) == pytest.approx(f * deg + want, abs=1e-6)


def test_head_and_eyes_find_the_struck_piece(rig: Rig, groove_dir: Path) -> None:
    """Hits with 0.3 s of nothing before them (and 0.2 s after): at the onset, 120 ms after
    the gaze set off, head and eyes point within 25 degrees of the struck zone for 90 % of them
    (the head alone, before the gaze module, was 32-36 degrees off at the 90th percentile);
    the head never turns faster than 400 degrees a second (before: 570-1660)."""
    note_map = load_note_map("roland-td")
    f = SecondaryParams().look_fraction
    errors, speeds = [], []
    for name in FILES:
        done = perform(read_midi_file(groove_dir / name, note_map), rig, note_map)
        st, anim = done.sticking, done.animation
        t_on = st.onsets["time_s"].astype(np.float64)
        hands = np.flatnonzero((st.limb >= 0) & (st.limb <= 1) & (st.piece >= 0))
        th = t_on[hands]
        alone = (np.diff(th, prepend=-np.inf) >= 0.3) & (np.diff(th, append=np.inf) >= 0.2)
        pick = hands[alone]
        point, _, _ = rig.targets.lookup(
            st.piece[pick].astype(np.int64), st.onsets["zone"][pick].astype(np.int64)
        )
        wq, wp = anim.world(t_on[pick])
        g = gaze_direction(wq[:, J["head"]], f, 0.0, P)
        want = azimuth(point - wp[:, J["head"]])
        errors.append(np.degrees(np.abs(azimuth(g) - want)))
        ts = np.arange(1.0, 20.0, 0.01)
        wq2, _ = anim.world(ts)
        fwd = quat.rotate(wq2[:, J["head"]], np.broadcast_to([0.0, 1.0, 0.0], (ts.size, 3)))
        speeds.append(np.degrees(np.abs(np.diff(azimuth(fwd)))) / 0.01)
    err = np.concatenate(errors)
    assert err.size >= 30
    assert np.percentile(err, 90) <= 25.0 and np.median(err) <= 15.0
    assert np.concatenate(speeds).max() <= 400.0
