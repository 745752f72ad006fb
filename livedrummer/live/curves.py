"""The live synth's curve set: the body's current curves and the cross-fade from the old ones.

Why this shape. The synth re-animates its window of notes whenever the notes change (see
:mod:`livedrummer.live.synth`); the new curves must not jump away from what the display is
showing, so for a short while after each rebuild a sample is a blend of the old curves and
the new. This module owns exactly that: the current :class:`Curves`, the previous ones while
the fade lasts, the fade itself, the clearance search's memo carried from one window to the
next, and how often the body was re-run. Everything else of the synth (which notes, which
samples were published) lives elsewhere.

The blend is :func:`~livedrummer.body.blend.blend_rows` (slerped rotations, bones rebuilt by
forward kinematics, so every bone keeps its length mid-fade). A fade's weight rises linearly
from its start to its end; the synth ends it at the next contact, so every contact is sampled
from the new curves alone.

:func:`sample_curves` is pure (a :class:`CurveView` is a frozen snapshot), so a quick
contact can sample the curves without touching the set. Limits: the stick guard
(:func:`~livedrummer.body.animation.guard_sticks`) is not run again on blended samples (each
side of the blend was guarded; their blend may graze a piece for a few milliseconds).

Where the curves live. :class:`CurveSource` is what the synth needs of a curve set: rebuild,
sample, the current curves' key and contacts. :class:`CurveSet` is the in-process one; the
synth service passes a worker process that holds a :class:`CurveSet` of its own
(:mod:`services.synth.curveworker`), so that the re-animation does not hold the service's
interpreter while a hit is being answered. Only an in-process set has a :meth:`CurveSet.view`
a quick contact can sample (a worker's view is empty: a quick contact then starts from the
samples published, as it does whenever there are any).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from livedrummer.body.animation import Animation, ClearanceMemo, Openness, animate
from livedrummer.body.blend import blend_rows
from livedrummer.body.expression import Expression
from livedrummer.body.rig import Rig
from livedrummer.body.sample import sample_poses
from livedrummer.body.strokes import StrokeParams
from livedrummer.live.style import StyleChange
from livedrummer.sticking.result import Sticking

Answer = Callable[[], None]


@dataclass(frozen=True)
class Curves:
    """One animation of the synthesizer's window, and what it was built from."""

    anim: Animation
    sticking: Sticking
    key: tuple[object, ...]
    contacts_s: np.ndarray  # committed contacts (performance time), sorted
    chokes: list[np.ndarray] | None = None  # per piece, choke (grab) times in the window
    #: a change of expression under way: the window animated with the old expression too
    style: tuple[StyleChange, Animation] | None = None


def sample_one(curves: Curves, times: np.ndarray, answer: Answer | None = None) -> np.ndarray:
    """Pose records of ``curves`` at ``times``, blended from the old expression's animation
    while a change of expression is under way (see :mod:`livedrummer.live.style`)."""
    rows = sample_poses(curves.anim, curves.sticking, times, curves.chokes)
    if curves.style is None:
        return rows
    change, old_anim = curves.style
    w = change.weight(times)
    mixed = w < 1.0
    if mixed.any():
        if answer is not None:
            answer()
        prev = sample_poses(old_anim, curves.sticking, times[mixed], curves.chokes)
        rows[mixed] = blend_rows(curves.anim.rig, prev, rows[mixed], w[mixed])
    return rows


@dataclass(frozen=True)
class CurveView:
    """A read-only snapshot of a :class:`CurveSet`: the curves, and the ones being faded out
    with the fade's (start, length) in performance time."""

    curves: Curves | None
    old: Curves | None = None
    fade: tuple[float, float] = (0.0, 0.0)


def sample_curves(
    view: CurveView, times: np.ndarray, answer: Answer | None = None
) -> tuple[np.ndarray, bool]:
    """Pose records at ``times``, cross-faded from ``view.old`` over its fade; and whether the
    fade is over for all of them (then the old curves can be dropped). ``answer``: called
    between the two samplings (see :func:`~livedrummer.body.animation.animate`)."""
    curves = view.curves
    if curves is None:
        raise ValueError("no curves to sample yet")
    rows = sample_one(curves, times, answer)
    old = view.old
    if old is None:
        return rows, True
    f0, flen = view.fade
    w = np.clip((times - f0) / flen, 0.0, 1.0) if flen > 0 else np.ones_like(times)
    fading = w < 1.0
    if not fading.any():
        return rows, True
    if answer is not None:
        answer()
    prev = sample_one(old, times[fading])
    rows[fading] = blend_rows(curves.anim.rig, prev, rows[fading], w[fading])
    return rows, False


class Built(Protocol):
    """What the synth reads of the current curves: their key and committed contacts."""

    @property
    def key(self) -> tuple[object, ...]: ...

    @property
    def contacts_s(self) -> np.ndarray: ...


class CurveSource(Protocol):
    """What :class:`~livedrummer.live.synth.LiveSynth` needs of its curves (see the module
    docstring): :class:`CurveSet`, or a worker process holding one."""

    animations: int
    built_at: float

    @property
    def current(self) -> Built | None: ...

    def view(self) -> CurveView: ...

    def reset(self) -> None: ...

    def rebuild(
        self,
        sticking: Sticking,
        beats: np.ndarray,
        openness: Openness,
        key: tuple[object, ...],
        contacts_s: np.ndarray,
        chokes: list[np.ndarray] | None,
        start_s: float,
        horizon_s: float,
        answer: Answer | None = None,
        expression: Expression | None = None,
        change: StyleChange | None = None,
    ) -> object: ...

    def sample(self, times: np.ndarray, answer: Answer | None = None) -> np.ndarray: ...


class CurveSet:
    """The current curves and the fade from the previous ones (see the module docstring)."""

    def __init__(self, rig: Rig, blend_s: float, strokes: StrokeParams | None = None) -> None:
        self.rig = rig
        self.blend_s = blend_s
        self.strokes = strokes or StrokeParams()
        self.reset()

    def reset(self) -> None:
        self._view = CurveView(None)
        self._memo: ClearanceMemo = {}  # the clearance search's settings, window to window
        self._memo_old: ClearanceMemo = {}  # the same for the old expression during a change
        self.animations = 0  # how many times the body was re-run (for benchmarks)
        self.built_at = -math.inf  # the committed horizon of the last rebuild

    @property
    def current(self) -> Curves | None:
        return self._view.curves

    def view(self) -> CurveView:
        return self._view

    def rebuild(
        self,
        sticking: Sticking,
        beats: np.ndarray,
        openness: Openness,
        key: tuple[object, ...],
        contacts_s: np.ndarray,
        chokes: list[np.ndarray] | None,
        start_s: float,
        horizon_s: float,
        answer: Answer | None = None,
        expression: Expression | None = None,
        change: StyleChange | None = None,
    ) -> Curves:
        """Animate ``sticking`` with ``expression`` (``answer`` is called between the steps)
        and, while a ``change`` of expression is under way, with its old expression too; make
        it current, fading from the old curves from ``start_s`` until the first of
        ``contacts_s`` (the sorted times of its committed notes, guesses left out) after it,
        at most ``blend_s``."""
        anim = animate(
            self.rig,
            sticking,
            beats,
            openness,
            expression,
            strokes=self.strokes,
            pause=answer,
            memo=self._memo,
        )
        self.animations += 1
        style = None
        if change is not None:
            old_anim = animate(
                self.rig,
                sticking,
                beats,
                openness,
                change.old,
                strokes=self.strokes,
                pause=answer,
                memo=self._memo_old,
            )
            style = (change, old_anim)
        self.built_at = horizon_s
        new = Curves(anim, sticking, key, contacts_s, chokes, style)
        old = self._view.curves
        if old is None:
            self._view = CurveView(new)
        else:
            nxt = contacts_s[contacts_s > start_s]
            length = self.blend_s if nxt.size == 0 else min(self.blend_s, float(nxt[0]) - start_s)
            self._view = CurveView(new, old, (start_s, max(length, 0.0)))
        return new

    def sample(self, times: np.ndarray, answer: Answer | None = None) -> np.ndarray:
        """Pose records of the current curves at ``times`` (see :func:`sample_curves`); the old
        curves are dropped once the fade is over."""
        rows, done = sample_curves(self._view, times, answer)
        if done and self._view.old is not None:
            self._view = CurveView(self._view.curves)
        return rows
