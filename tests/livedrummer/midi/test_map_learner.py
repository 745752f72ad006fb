"""The map learner as pure logic: a pad that sends several notes for one hit teaches one."""

from __future__ import annotations

import mido

from livedrummer.midi.learn import SAME_HIT_S, MapLearner


def hit(note: int) -> mido.Message:
    return mido.Message("note_on", channel=9, note=note, velocity=100)


def test_a_hit_sending_several_notes_answers_one_prompt() -> None:
    learner = MapLearner("dtx6")
    # A DTX-PRO input with Note.1 and Note.2 set: 36 and 35 for one kick, 1 ms apart.
    assert learner.feed(hit(36), 10.000) == "Kick: note 36"
    said = learner.feed(hit(35), 10.001)
    assert said is not None and "note 35 came in the same hit as note 36 (Kick)" in said
    assert learner.prompt is not None and learner.prompt[3] == "Snare head"  # still asked
    # the drummer hits the snare after reading the prompt, which sends 38 and 40
    assert learner.feed(hit(38), 10.600) == "Snare head: note 38"
    assert learner.feed(hit(40), 10.600 + SAME_HIT_S / 2) is not None
    assert learner.feed(hit(40), 11.300) == "Snare rim (rim shot): note 40"
    assert {n: d.label for n, d in learner.notes().items()} == {
        36: "Kick",
        38: "Snare head",
        40: "Snare rim (rim shot)",
    }


def test_without_times_every_new_note_answers_the_next_prompt() -> None:
    learner = MapLearner("plain")
    assert learner.feed(hit(36)) == "Kick: note 36"
    assert learner.feed(hit(35)) == "Snare head: note 35"
