"""One call from a performance to an animated body: sticking, hi-hat pedal, torso, strokes.

The CLI commands, benchmarks and services all start here, so they cannot disagree on how a
performance is animated. Limb assignment is not done here but taken as given: the caller
passes the :class:`~livedrummer.sticking.result.Sticking` that
:func:`~livedrummer.sticking.strategy.stick_performance` made (strategy, beat grid, edited
score), which is exactly what ``livedrummer sticking`` prints; without one, that function's
default (``optimal`` on the performance's grid) is used. The animation plays the limbs of that
sticking unchanged, so :attr:`Performed.sticking` is the limb of every note as animated.

Two cut lists per kit piece come with it: :attr:`Performed.chokes`, the grabs the body plays
(a cymbal stops swinging), and :attr:`Performed.sound_chokes`, what stops a ringing sound (the
grabs and the hi-hat pedal closing, :func:`~livedrummer.audio.cuts.sound_chokes`): every
offline track (render, export, the file window) mixes with the second, as the live sound cuts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.audio.cuts import sound_chokes
from livedrummer.body.animation import Animation, animate, hihat_openness
from livedrummer.body.expression import Expression
from livedrummer.body.rig import Rig
from livedrummer.body.sample import choke_times
from livedrummer.body.secondary import SecondaryParams
from livedrummer.body.strokes import StrokeParams
from livedrummer.midi.notemap import NoteMap
from livedrummer.sticking.result import Sticking
from livedrummer.sticking.strategy import stick_performance
from livedrummer.timeline.performance import Performance


@dataclass(frozen=True)
class Performed:
    sticking: Sticking
    animation: Animation
    chokes: list[np.ndarray]  # grabs, per kit piece: where the picture's cymbal stops
    sound_chokes: list[np.ndarray]  # grabs and the pedal closing: where the sound stops


def perform(
    performance: Performance,
    rig: Rig,
    note_map: NoteMap,
    expression: Expression | None = None,
    strokes: StrokeParams | None = None,
    secondary: SecondaryParams | None = None,
    sticking: Sticking | None = None,
) -> Performed:
    """Animate ``performance`` on ``rig`` with ``sticking`` (see the module docstring)."""
    st = sticking if sticking is not None else stick_performance(performance, rig.kit)
    if st.onsets.size != performance.onsets.size:
        raise ValueError("the sticking is not of this performance (another number of notes)")
    if st.onsets.size and np.any(np.diff(st.onsets["time_s"]) < 0):
        raise ValueError("a sticking's onsets must be sorted by time")
    cc_open = np.array([note_map.openness(v) for v in range(128)])
    openness = hihat_openness(performance.onsets, performance.controls, cc_open=cc_open)
    anim = animate(rig, st, performance.grid.beat_s, openness, expression, strokes, secondary)
    return Performed(
        st,
        anim,
        choke_times(performance.controls, note_map, anim),
        sound_chokes(performance.controls, note_map, rig.kit),
    )
