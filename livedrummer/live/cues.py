"""Cue lists: SMED's "local control" per section, as a TOML file of named cues.

A cue sets any of: an expression preset, expression parameters (on top of the preset, or of
what is playing), the camera (a smooth move, or a cut), the blackout and the show lights (a
look and light parameters, faded over ``fade_s``). It fires at a time
(``at_s``, seconds from the start of a file), at a bar (``bar``, 1-based, on the file's bar
grid), or only when called by name (OSC ``/livedrummer/cue NAME``)::

    [[cue]]
    name = "verse"
    bar = 5
    preset = "relaxed"
    camera = "front"        # a name or 1-8
    cut = false             # true: cut to the camera, no move
    blackout = false
    look = "neon"           # the show lights' theme (livedrummer.kit.lights.LOOKS)
    fade_s = 2.0            # the light change takes this long (default 0: at once)
    [cue.params]
    head_amplitude_deg = 10.0
    [cue.lights]            # light parameters over the look (as a kit's [lights] table)
    key = { intensity = 4.0, color = "#ffd0a0" }
    rim = { enabled = false }

Why this shape. A cue is plain data (:class:`Cue`, loaded strictly: unknown keys, a bad
parameter or camera name the file and the cue); :func:`cue_times` puts them on a timeline,
and :func:`expression_at` folds the ones fired so far into the expression in force, so the
file renderer and the live services apply the same cue the same way: the synth takes its
preset and parameters, the display its camera, blackout and lights (a cue's light change
applies over the lights as they are when it fires).

Live, bars are counted by the beat tracker (:meth:`livedrummer.live.beat.BeatTracker.bars`: bar
1 is the first bar it hears start once it has a tempo, 4/4 assumed) and :class:`BarCues` fires
each ``bar`` cue once, when its bar starts (or at the next bar start, should a stalled caller
have skipped its number; a corrected downbeat never does), with that bar's start time (the
synth asks a moment ahead of the predicted start, so the cue is on time). The synth eases in
its style from the bar, and sends its camera and blackout to every display
(:func:`stage_cue_rows`, protocol kind STAGE_CUE) stamped with the bar's show time (its start +
D); a display turns a row back into a cue (:func:`stage_cue_of`) and applies it with
:func:`fire_stage` when a frame reaches that show time, the one function that applies a cue to
a :class:`~livedrummer.live.stage.Stage`.

The wire's STAGE_CUE row carries the camera and blackout only: a display given the same cue
list (``up --cues`` gives it to both) takes a bar cue's lights from its own copy
(:func:`with_lights_of`). Limits: bars are counted on a file's tempo map and meter (live: the
tracker's, 4/4); a cue's preset is read when the list is loaded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from livedrummer.body.expression import PARAM_NAMES, Expression, load_expression, with_param
from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError, LivedrummerError
from livedrummer.kit.lights import LOOKS, LightRig, LightSpec, parse_light_spec
from livedrummer.live.stage import Stage, camera_name
from livedrummer.render.camera import CAMERA_NAMES, Camera
from livedrummer.timeline.events import STAGE_CUE_DTYPE


class CueError(ConfigError):
    """A cue list that cannot be used (file, cue and key named)."""


@dataclass(frozen=True)
class Cue:
    name: str
    at_s: float | None = None
    bar: int | None = None
    preset: str | None = None
    expression: Expression | None = None  # the preset, loaded
    params: tuple[tuple[str, float], ...] = ()
    camera: str | None = None
    cut: bool = False
    blackout: bool | None = None
    lights: LightSpec | None = None  # a look and light parameters, over the lights in force
    fade_s: float = 0.0  # how long the light change takes

    def apply(self, base: Expression) -> Expression:
        """The expression after this cue: its preset (else ``base``) with its parameters."""
        out = self.expression if self.expression is not None else base
        for name, value in self.params:
            out = with_param(out, name, value)
        return out

    @property
    def styles(self) -> bool:
        return self.expression is not None or bool(self.params)

    @property
    def stages(self) -> bool:
        """Whether it moves the camera, the blackout or the lights (a display's part)."""
        return self.camera is not None or self.blackout is not None or self.lights is not None


def parse_cues(data: dict[str, object], source: str) -> dict[str, Cue]:
    root = Table(data, source, "", CueError)
    out: dict[str, Cue] = {}
    for t in root.tables("cue", "name"):
        name = t.text("name")
        if name in out:
            raise t.fail("name", "a second cue of that name", name)
        at_s = t.number("at_s", None, lo=0.0)
        bar = t.integer("bar", None, lo=1)
        if at_s is not None and bar is not None:
            raise t.fail("bar", "give at_s or bar, not both")
        preset = t.text("preset", None)
        expression = None
        if preset is not None:
            try:
                expression = load_expression(preset)
            except LivedrummerError as exc:
                raise t.fail("preset", str(exc)) from None
        params: list[tuple[str, float]] = []
        pt = t.table("params") if t.has("params") else Table({}, source, "", CueError)
        for key in pt.keys():
            if key not in PARAM_NAMES:
                raise pt.fail(key, "no such expression parameter")
            p = PARAM_NAMES[key]
            params.append((key, pt.number(key, lo=p.lo, hi=p.hi)))
        pt.done()
        try:
            camera = t.text("camera", None)
        except CueError:  # a number 1-8, as the window's keys
            camera = str(t.integer("camera", lo=1, hi=8))
        if camera is not None:
            try:
                camera = camera_name(camera)
            except ValueError as exc:
                raise t.fail("camera", str(exc)) from None
        cut = t.boolean("cut", False)
        blackout = t.boolean("blackout") if t.has("blackout") else None
        look = t.text("look", None, choices=LOOKS)
        lights = parse_light_spec(t.table("lights")) if t.has("lights") else None
        if look is not None:
            if lights is not None and lights.look is not None:
                raise t.fail("look", "given twice: here and in [cue.lights]", look)
            lights = LightSpec(look) if lights is None else replace(lights, look=look)
        fade_s = t.number("fade_s", 0.0, lo=0.0, hi=600.0)
        if t.has("fade_s") and lights is None:
            raise t.fail("fade_s", "fades a light change: give look or [cue.lights] too")
        t.done()
        out[name] = Cue(
            name,
            at_s,
            bar,
            preset,
            expression,
            tuple(params),
            camera,
            cut,
            blackout,
            lights,
            fade_s,
        )
    root.done()
    return out


def load_cues(path: Path | str) -> dict[str, Cue]:
    """The cues of a TOML file, by name (see the module docstring)."""
    return parse_cues(read_toml(Path(path), CueError), str(path))


def cue_times(cues: dict[str, Cue], bar_s: np.ndarray | None = None) -> list[tuple[float, Cue]]:
    """The timed cues, by time: ``at_s``, or the start of bar ``bar`` (``bar_s``: each bar's
    start in seconds, bar 1 first); a bar past the end never fires."""
    out: list[tuple[float, Cue]] = []
    for cue in cues.values():
        if cue.at_s is not None:
            out.append((cue.at_s, cue))
        elif cue.bar is not None and bar_s is not None and cue.bar <= bar_s.size:
            out.append((float(bar_s[cue.bar - 1]), cue))
    out.sort(key=lambda tc: tc[0])
    return out


def expression_at(timed: list[tuple[float, Cue]], t: float, base: Expression) -> Expression:
    """The expression in force at ``t`` after the cues fired by then."""
    out = base
    for at, cue in timed:
        if at > t:
            break
        out = cue.apply(out)
    return out


def style_changes(
    timed: list[tuple[float, Cue]], base: Expression
) -> list[tuple[float, Expression]]:
    """(time, expression from then on) at each cue that changes the style, from -inf."""
    out = [(-math.inf, base)]
    for at, cue in timed:
        if cue.styles:
            out.append((at, cue.apply(out[-1][1])))
    return out


class CuedStage:
    """A :class:`~livedrummer.live.stage.Stage` driven by timed cues: :meth:`at` fires the
    cues due by a frame's time (frames asked in time order) and gives its camera and
    darkness; :meth:`lights_at` then gives its lights."""

    def __init__(self, stage: Stage, timed: list[tuple[float, Cue]]) -> None:
        self.stage = stage
        self._pending = [(t, c) for t, c in timed if c.stages]
        self._next = 0

    def at(self, t: float) -> tuple[Camera, float]:
        while self._next < len(self._pending) and self._pending[self._next][0] <= t:
            at, cue = self._pending[self._next]
            fire_stage(self.stage, cue, at)
            self._next += 1
        return self.stage.view(t), self.stage.darkness(t)

    def lights_at(self, t: float) -> LightRig:
        return self.stage.lights_at(t)


def fire_stage(stage: Stage, cue: Cue, now_s: float) -> None:
    """A cue's camera, blackout and lights, applied at ``now_s``."""
    if cue.camera is not None:
        stage.set_camera(cue.camera, now_s, cut=cue.cut)
    if cue.blackout is not None:
        stage.set_blackout(cue.blackout, now_s)
    if cue.lights is not None:
        stage.set_lights(cue.lights.apply(stage.lights), now_s, cue.fade_s)


class BarCues:
    """The ``bar`` cues of a list, fired live as bars are counted: :meth:`due` takes the bar
    starts heard since the last call, (start time, bar number), and gives the cues due, each
    once, in bar order, with the start of the first bar given at or past the cue's bar."""

    def __init__(self, cues: dict[str, Cue]) -> None:
        self._pending = sorted(
            (c for c in cues.values() if c.bar is not None), key=lambda c: c.bar or 0
        )

    def due(self, bars: list[tuple[float, int]]) -> list[tuple[float, Cue]]:
        if not bars or not self._pending:
            return []
        reached = max(bar for _, bar in bars)
        out = [c for c in self._pending if (c.bar or 0) <= reached]
        self._pending = self._pending[len(out) :]
        return [(min(t for t, bar in bars if bar >= (c.bar or 0)), c) for c in out]


def stage_cue_rows(fired: list[tuple[float, int, Cue]]) -> np.ndarray:
    """The stage part of cues fired at (show time, bar, cue), as STAGE_CUE_DTYPE rows (the
    wire's kind STAGE_CUE); cues without one are left out."""
    fired = [f for f in fired if f[2].stages]  # a lights-only row: its bar, for with_lights_of
    out = np.zeros(len(fired), STAGE_CUE_DTYPE)
    for i, (show_s, bar, cue) in enumerate(fired):
        camera = 0 if cue.camera is None else CAMERA_NAMES.index(cue.camera) + 1
        blackout = -1 if cue.blackout is None else int(cue.blackout)
        out[i] = (show_s, bar, camera, int(cue.cut), blackout)
    return out


def stage_cue_of(row: np.void) -> Cue:
    """A STAGE_CUE row back as the cue it came from (its stage part; named after its bar)."""
    camera = int(row["camera"])
    blackout = int(row["blackout"])
    bar = int(row["bar"])
    return Cue(
        f"bar {bar}",
        bar=bar or None,
        camera=CAMERA_NAMES[camera - 1] if camera else None,
        cut=bool(row["cut"]),
        blackout=None if blackout < 0 else bool(blackout),
    )


def with_lights_of(cue: Cue, cues: dict[str, Cue]) -> Cue:
    """A STAGE_CUE row's cue (:func:`stage_cue_of`) with the lights of the bar cue of
    ``cues`` it came from (the row carries no lights); itself when there is none."""
    if cue.bar is None:
        return cue
    for own in cues.values():
        if own.bar == cue.bar and own.lights is not None:
            return replace(cue, lights=own.lights, fade_s=own.fade_s)
    return cue
