"""``bench answer``: every stage of the answer path timed, and the wrapped functions restored."""

from __future__ import annotations

from collections import defaultdict

from livedrummer.body.rig import Rig
from livedrummer.live import synth, window
from livedrummer.timeline.performance import Performance
from services.bench import answer


def test_every_stage_is_timed_and_the_functions_are_restored(rig: Rig, groove: Performance) -> None:
    before = (window.NoteWindow.add, synth.LiveSynth.take_quick)
    onsets = answer.alternating(groove.onsets, 40.0, 0.2)
    assert onsets.size == 8 and set(onsets["note"].tolist()) == {38, 42}
    times: answer.Times = defaultdict(list)
    answers = answer.drive(rig, onsets, times)
    assert 1 <= answers.size <= onsets.size
    for _, _, label in answer.STAGES[:7]:
        assert times[label], f"{label} was not timed"
    assert len(times["decode ONSET"]) == answers.size
    assert (window.NoteWindow.add, synth.LiveSynth.take_quick) == before
