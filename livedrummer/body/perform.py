"""One call from a performance to an animated body: sticking, hi-hat pedal, torso, strokes.

The CLI commands, benchmarks and (later) services all start here, so they cannot disagree on
how a performance is animated. Limb assignment is a parameter: the ``optimal`` strategy of
:mod:`livedrummer.sticking` by default; :func:`fallback_sticking` (preferred limbs with simple
alternation) stays selectable as ``"fallback"`` for comparison.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from livedrummer.body.animation import Animation, animate, hihat_openness
from livedrummer.body.expression import Expression
from livedrummer.body.fallback_sticking import fallback_sticking
from livedrummer.body.rig import Rig
from livedrummer.body.sample import choke_times
from livedrummer.body.secondary import SecondaryParams
from livedrummer.body.strokes import StrokeParams
from livedrummer.errors import LivedrummerError
from livedrummer.kit import Kit
from livedrummer.notemap import NoteMap
from livedrummer.performance import Performance
from livedrummer.sticking.result import Sticking

StickingFn = Callable[[np.ndarray, Kit, np.ndarray], Sticking]


def named_sticking(name: str) -> StickingFn:
    """``"fallback"`` or a strategy of :mod:`livedrummer.sticking` (by its name)."""
    if name == "fallback":
        return fallback_sticking
    from livedrummer.sticking import STRATEGIES, assign

    if name not in STRATEGIES:
        known = ", ".join(["fallback", *sorted(STRATEGIES)])
        raise LivedrummerError(f"unknown sticking strategy {name!r} (known: {known})")

    def run(onsets: np.ndarray, kit: Kit, hand_ok: np.ndarray) -> Sticking:
        return assign(onsets, kit, name)

    return run


@dataclass(frozen=True)
class Performed:
    sticking: Sticking
    animation: Animation
    chokes: list[np.ndarray]


def perform(
    performance: Performance,
    rig: Rig,
    note_map: NoteMap,
    expression: Expression | None = None,
    strokes: StrokeParams | None = None,
    secondary: SecondaryParams | None = None,
    sticking: StickingFn | None = None,
) -> Performed:
    assign = sticking if sticking is not None else named_sticking("optimal")
    st = assign(performance.onsets, rig.kit, rig.hand_ok)
    if st.onsets.size and np.any(np.diff(st.onsets["time_s"]) < 0):
        raise ValueError("a sticking's onsets must be sorted by time")
    cc_open = np.array([note_map.openness(v) for v in range(128)])
    openness = hihat_openness(performance.onsets, performance.controls, cc_open=cc_open)
    anim = animate(rig, st, performance.grid.beat_s, openness, expression, strokes, secondary)
    return Performed(st, anim, choke_times(performance.controls, note_map, anim))
