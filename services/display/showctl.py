"""The live display's show control: camera, blackout and lights, from OSC and from bar cues,
applied frame by frame.

Why here and not in the loop. The display's loop draws frames; what the audience sees besides
the drummer (the camera, the blackout, the show lights) is the pure
:class:`~livedrummer.live.stage.Stage`, fed by this module from two sources: an
:class:`~services.show.osc.OscEndpoint` (``display --osc PORT``, or ``up --osc``'s forwarding), and
the synth's STAGE_CUE messages (a ``bar`` cue's camera and blackout, sent when the synth's beat
tracker reaches the bar, stamped with the bar's show time; the loop hands them to
:meth:`DisplayShow.schedule`, which takes a bar cue's lights from its own copy of the cue list,
as the row carries none). OSC ``/livedrummer/look NAME [FADE_S]`` and
``/livedrummer/light/LIGHT/PARAM VALUE... [FADE_S]`` become cues too (:func:`light_cue`), so a
light change is replayed like a camera move. :meth:`DisplayShow.apply` runs on the loop's
thread before each frame: an OSC command reaches the very next frame drawn (the OSC socket only
queues it), a stage cue the first frame whose show time reaches the cue's, applied as of that
show time (a render time ``show - cue`` earlier than the frame's, so a fade starts on the bar,
not a frame late). Every change goes through :meth:`DisplayShow.fire`, as a
:class:`~livedrummer.live.cues.Cue` applied by :func:`~livedrummer.live.cues.fire_stage`, and
is kept in :attr:`DisplayShow.history`, from which a set-length recording drawn after the show
replays the stage (:func:`replay_stage`). The stage is read by the surface that draws
(:mod:`services.display.surface`); :func:`darken` blends black over a drawn frame (the
blackout's fade) through the renderer's overlay pass, so PNGs, recordings and the window all
see it.

Limits: a stage cue that arrives after its show time (the synth later than D) is applied at
once, as of its time (a fade already under way); black frames are drawn, not skipped; a
window with a stage (``--osc`` or ``--cues``) takes its camera from it, so the mouse does
not orbit there.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from livedrummer.kit.lights import (
    LIGHT_NAMES,
    LOOKS,
    LightChange,
    LightError,
    LightRig,
    LightSpec,
)
from livedrummer.kit.model import Kit
from livedrummer.live.cues import Cue, CuedStage, fire_stage, stage_cue_of, with_lights_of
from livedrummer.live.stage import Stage, camera_name

from ..show.osc import (
    CUE,
    DISPLAY_ADDRESSES,
    LIGHT,
    LOOK,
    PREFIX,
    STATE,
    Arg,
    Command,
    OscEndpoint,
    state_pairs,
)

log = logging.getLogger("livedrummer.display")


class DisplayShow:
    """The stage and what steers it (see the module docstring); ``port`` None: no OSC."""

    def __init__(
        self,
        kit: Kit,
        camera: str,
        port: int | None,
        allow: tuple[str, ...] = (),
        cues: dict[str, Cue] | None = None,
        lights: LightRig | None = None,
    ) -> None:
        self.stage = Stage(kit, camera, lights=lights)
        self.camera = camera  # the first one, for a replay
        self.lights = self.stage.lights  # the first ones, for a replay
        self.cues = cues or {}
        self.osc = (
            None if port is None else OscEndpoint(port, DISPLAY_ADDRESSES, "display", log, allow)
        )
        self.frames = 0
        self.history: list[tuple[float, Cue]] = []  # (render time, change), as applied
        # stage cues waiting for their show time: (show time, cue, arrived after a frame
        # that should have shown it)
        self._timed: list[tuple[float, Cue, bool]] = []
        self.stage_cues = 0  # stage cues received from the synth
        self.late_cues = 0  # ... of which arrived after the frame that should have shown them
        self._shown_s = -math.inf  # the show time of the last frame

    def schedule(self, rows: np.ndarray) -> None:
        """STAGE_CUE rows from the synth: applied when a frame's show time reaches theirs."""
        for row in rows:
            at_s = float(row["time_s"])
            late = at_s <= self._shown_s
            self._timed.append((at_s, with_lights_of(stage_cue_of(row), self.cues), late))
            if late:
                self.late_cues += 1
                log.warning(
                    "display: a stage cue (bar %d) arrived %.0f ms after its show time: "
                    "it took this machine longer than the show delay (--delay-ms), "
                    "so the cue is applied in the next frame",
                    int(row["bar"]),
                    1000 * (self._shown_s - at_s),
                )
        self._timed.sort(key=lambda tc: tc[0])
        self.stage_cues += rows.size

    def apply(self, now_s: float, show_s: float | None = None) -> list[tuple[str, float, bool]]:
        """Before the frame drawn at the display's clock ``now_s`` for show time ``show_s``:
        every OSC command received since the last frame, and the stage cues due by
        ``show_s``; gives the stage cues applied, (name, show time, arrived late), for the
        frame's log."""
        if self.osc is not None:
            for cmd in self.osc.take():
                self.command(cmd, now_s)
        fired: list[tuple[str, float, bool]] = []
        while show_s is not None and self._timed and self._timed[0][0] <= show_s:
            at_s, cue, late = self._timed.pop(0)
            self.fire(cue, now_s - (show_s - at_s))
            fired.append((cue.name, at_s, late))
            log.info(
                "display: %s: %s at show %.3f s (frame %d)",
                cue.name,
                describe(cue),
                at_s,
                self.frames,
            )
        if show_s is not None:
            self._shown_s = show_s
        self.frames += 1
        return fired

    def fire(self, cue: Cue, now_s: float) -> None:
        """Apply a cue's camera and blackout at the display's clock ``now_s`` (every change
        to the stage comes here), and keep it for a replay."""
        fire_stage(self.stage, cue, now_s)
        self.history.append((now_s, cue))

    def command(self, cmd: Command, now_s: float) -> None:
        stage, args = self.stage, cmd.args
        if self.osc is None:
            return
        if cmd.address == STATE:
            self.osc.reply(
                cmd.sender,
                STATE,
                state_pairs(
                    {
                        "camera": stage.camera,
                        "blackout": int(stage.blackout),
                        "look": stage.lights.name,
                        "frames": self.frames,
                    }
                ),
            )
            return
        if cmd.address == LOOK or cmd.address.startswith(LIGHT):
            self._light_command(self.osc, cmd, now_s)
            return
        if len(args) != 1:
            self.osc.argument(cmd, "expected one argument")
            return
        try:
            if cmd.address == CUE:
                cue = self.cues.get(args[0]) if isinstance(args[0], str) else None
                if cue is None:
                    raise ValueError(f"no cue of that name (known: {', '.join(self.cues)})")
            elif cmd.address == PREFIX + "blackout":
                if isinstance(args[0], str) or args[0] not in (0, 1):
                    raise ValueError("expected 0 or 1")
                cue = Cue(cmd.address, blackout=bool(args[0]))
            else:
                value = args[0]
                name = camera_name(value if isinstance(value, str) else float(value))
                cue = Cue(cmd.address, camera=name, cut=cmd.address.endswith("/cut"))
        except ValueError as exc:
            self.osc.argument(cmd, str(exc))
            return
        self.fire(cue, now_s)
        log.info("display: %s %s", cmd.address, args[0])

    def _light_command(self, osc: OscEndpoint, cmd: Command, now_s: float) -> None:
        try:
            cue = light_cue(cmd.address, cmd.args, self.stage.lights)
        except ValueError as exc:
            osc.argument(cmd, str(exc))
            return
        self.fire(cue, now_s)
        log.info("display: %s %s", cmd.address, " ".join(str(a) for a in cmd.args))

    def close(self) -> None:
        if self.osc is not None:
            self.osc.stop()


def _number(value: Arg, what: str) -> float:
    if isinstance(value, str):
        raise ValueError(f"{what}: expected a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{what}: {value!r} is not a number")
    return v


#: How many values each OSC light parameter takes (a trailing one more is the fade, seconds).
_LIGHT_ARITY = {"color": 3, "direction": 2}


def light_cue(address: str, args: tuple[Arg, ...], rig: LightRig) -> Cue:
    """The cue of an OSC look or light command (see the module docstring), checked against
    the rig in force; ValueError saying what is wrong."""
    changes: list[LightChange] = []
    if address == LOOK:
        if not 1 <= len(args) <= 2 or not isinstance(args[0], str):
            raise ValueError("expected a look name and an optional fade in seconds")
        if args[0] not in LOOKS:
            raise ValueError(f"look {args[0]!r}: expected one of {', '.join(LOOKS)}")
        spec = LightSpec(args[0])
        rest = args[1:]
    else:
        parts = address[len(LIGHT) :].split("/")
        if len(parts) != 2 or parts[0] not in LIGHT_NAMES:
            raise ValueError(f"expected {LIGHT}LIGHT/PARAM, LIGHT one of {', '.join(LIGHT_NAMES)}")
        light, param = parts
        n = _LIGHT_ARITY.get(param, 1)
        if param == "color" and args and isinstance(args[0], str):
            n = 1  # "#rrggbb"
        if not n <= len(args) <= n + 1:
            raise ValueError(f"expected {n} value{'s' * (n > 1)} and an optional fade in seconds")
        values, rest = args[:n], args[n:]
        if param == "direction":
            changes = [
                (light, "azimuth", _number(values[0], "azimuth")),
                (light, "elevation", _number(values[1], "elevation")),
            ]
        elif param == "color" and n == 3:
            changes = [(light, c, _number(v, c)) for c, v in zip("rgb", values, strict=True)]
        elif param == "color":
            changes = [(light, param, str(values[0]))]
        else:
            changes = [(light, param, _number(values[0], param))]
        spec = LightSpec(changes=tuple(changes))
    fade_s = _number(rest[0], "fade") if rest else 0.0
    if not 0.0 <= fade_s <= 600.0:
        raise ValueError(f"fade {fade_s:g} s: expected 0..600")
    try:
        spec.apply(rig)
    except LightError as exc:
        raise ValueError(str(exc)) from None
    return Cue(address, lights=spec, fade_s=fade_s)


def describe(cue: Cue) -> str:
    """A cue's stage part in words, for the log: "camera front (cut), blackout 1"."""
    parts = []
    if cue.camera is not None:
        parts.append(f"camera {cue.camera}" + (" (cut)" if cue.cut else ""))
    if cue.blackout is not None:
        parts.append(f"blackout {int(cue.blackout)}")
    if cue.lights is not None:
        what = [f"look {cue.lights.look}"] if cue.lights.look else []
        what += [f"{light} {param} {value}" for light, param, value in cue.lights.changes]
        parts.append(
            f"lights {', '.join(what) or 'as they are'}"
            + (f" over {cue.fade_s:g} s" if cue.fade_s else "")
        )
    return ", ".join(parts) or "nothing"


def replay_stage(kit: Kit, show: DisplayShow) -> CuedStage:
    """A fresh stage that replays ``show``'s changes: ``.at(render_s)`` before each frame of
    a recording drawn after the show puts the stage where it was at that frame."""
    return CuedStage(Stage(kit, show.camera, lights=show.lights), list(show.history))


_black: dict[tuple[int, int, int], np.ndarray] = {}


def darken(renderer: Any, darkness: float, target: Any = None) -> None:
    """Blend black at ``darkness`` (0..1) over the frame ``renderer`` drew last."""
    alpha = round(min(1.0, max(0.0, darkness)) * 255)
    if alpha <= 0:
        return
    w, h = renderer.size
    key = (w, h, alpha)
    image = _black.get(key)
    if image is None:
        _black.clear()  # one size and level at a time (a fade changes it every frame)
        image = np.zeros((h, w, 4), np.uint8)
        image[..., 3] = alpha
        _black[key] = image
    renderer.draw_overlay(image, (0, 0, w, h), target)
