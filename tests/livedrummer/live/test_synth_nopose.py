"""Every note of a fast stream gets its contact in the live synth, merged notes included.

Past 100 notes/s three hand notes fall inside the sticking's chord window; the one that no
third hand can strike is merged into the nearer stroke (:mod:`livedrummer.sticking.prepare`),
so the live synth shows it as a flam or double stroke of that hand: its own onset has a contact
sample at onset + D with the hand's tip on its piece. Notes stamped together by a loaded
machine (one stamp for a burst) share one instant: a hand is then on one of its notes' pieces.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_synth import ENDS, START, _target

from livedrummer.body.rig import Rig
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.sticking.online import stick_online
from livedrummer.sticking.result import merged_notes
from tests.livedrummer.sticking.test_sticking_nopose import stream


def play_live(synth: LiveSynth, onsets: np.ndarray) -> PoseTrack:
    """Each note on arrival, its quick contact taken as the service does, ticks between."""
    now = float(onsets["time_s"][0]) - 0.2
    track = PoseTrack(keep_s=20.0)
    for row in onsets:
        t = float(row["time_s"])
        while now + 1 / 120 < t:
            now += 1 / 120
            b = synth.poses_until(now)
            track.add(b.show_s, b.rows)
        now = max(now, t + 0.0005)
        synth.process(row)
        q = synth.take_quick()
        track.add(q.show_s, q.rows)
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
    for _ in range(60):
        now += 1 / 120
        b = synth.poses_until(now)
        track.add(b.show_s, b.rows)
    return track


@pytest.mark.parametrize(
    ("rate", "pattern", "stamps"),
    [
        (150.0, "snare-hihat", "exact"),
        (199.0, "snare", "exact"),
        (199.0, "mixed", "jittered"),
        (150.0, "snare-hihat", "bunched"),
    ],
)
def test_every_note_has_a_contact_on_its_piece(
    rig: Rig, rate: float, pattern: str, stamps: str
) -> None:
    on = stream(pattern, rate, stamps, seconds=0.6)
    on["time_s"] += START
    params = SynthParams()
    synth = LiveSynth(rig, params)
    track = play_live(synth, on)
    sticking = stick_online(on, rig.kit, params.lookahead_s)
    merged = merged_notes(sticking)
    assert merged.sum() >= 10  # the stream has notes no two hands strike separately
    assert synth.window.merged == merged.sum()  # what the service's warning counts
    played = np.flatnonzero(sticking.piece >= 0)
    assert (sticking.limb[played] >= 0).all(), "every note the kit has gets a limb"
    on_target: dict[tuple[float, int], list[bool]] = {}
    for i in played:
        limb = int(sticking.limb[i])
        show = float(sticking.onsets["time_s"][i]) + params.delay_s
        j = int(np.argmin(np.abs(track.show_s - show)))
        assert abs(track.show_s[j] - show) < 1e-9, f"note {i}: no sample at onset + D"
        target = _target(rig, sticking.onsets[i], limb, int(sticking.piece[i]))
        miss = float(np.linalg.norm(track.rows["position"][j, ENDS[limb]] - target))
        on_target.setdefault((show, limb), []).append(miss < 1e-3)
    if stamps == "bunched":  # one instant, one place per hand: on one of its notes
        assert all(any(hits) for hits in on_target.values())
    else:
        assert all(all(hits) for hits in on_target.values())
