"""The live display's show control: OSC camera and blackout commands applied frame by frame.

Why here and not in the loop. The display's loop draws frames; what the audience sees besides
the drummer (the camera, the blackout) is the pure :class:`~livedrummer.live.stage.Stage`,
fed by this module from an :class:`~services.osc.OscEndpoint` (``display --osc PORT``, or
``up --osc``'s forwarding). :meth:`DisplayShow.apply` runs on the loop's thread before each
frame, so a command reaches the very next frame drawn (the OSC thread only queues it), and
the stage is read by the surface that draws (:mod:`services.display.surface`).
:func:`darken` blends black over a drawn frame (the blackout's fade) through the renderer's
overlay pass, so PNGs, recordings and the window all see it.

Limits: a set-length headless recording (``up --video --seconds``), drawn after the show,
uses the camera it was started with; black frames are drawn, not skipped.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.live.cues import Cue, fire_stage
from livedrummer.live.stage import Stage

from ..osc import CUE, DISPLAY_ADDRESSES, PREFIX, STATE, Command, OscEndpoint, state_pairs

log = logging.getLogger("livedrummer.display")


class DisplayShow:
    """The stage and the OSC endpoint that steers it (see the module docstring)."""

    def __init__(self, kit: Kit, camera: str, port: int, allow: tuple[str, ...] = (),
                 cues: dict[str, Cue] | None = None) -> None:  # fmt: skip
        self.stage = Stage(kit, camera)
        self.cues = cues or {}
        self.osc = OscEndpoint(port, DISPLAY_ADDRESSES, "display", log, allow)
        self.frames = 0

    def apply(self, now_s: float) -> None:
        """Every command received since the last frame, at the display's clock ``now_s``."""
        for cmd in self.osc.take():
            self.command(cmd, now_s)
        self.frames += 1

    def command(self, cmd: Command, now_s: float) -> None:
        stage, args = self.stage, cmd.args
        if cmd.address == STATE:
            self.osc.reply(cmd.sender, STATE, state_pairs({
                "camera": stage.camera, "blackout": int(stage.blackout),
                "frames": self.frames,
            }))  # fmt: skip
            return
        if len(args) != 1:
            self.osc.argument(cmd, "expected one argument")
            return
        try:
            if cmd.address == CUE:
                cue = self.cues.get(args[0]) if isinstance(args[0], str) else None
                if cue is None:
                    raise ValueError(f"no cue of that name (known: {', '.join(self.cues)})")
                fire_stage(stage, cue, now_s)
            elif cmd.address == PREFIX + "blackout":
                if isinstance(args[0], str) or args[0] not in (0, 1):
                    raise ValueError("expected 0 or 1")
                stage.set_blackout(bool(args[0]), now_s)
            else:
                value = args[0]
                spec = value if isinstance(value, str) else float(value)
                stage.set_camera(spec, now_s, cut=cmd.address.endswith("/cut"))
        except ValueError as exc:
            self.osc.argument(cmd, str(exc))
            return
        log.info("display: %s %s", cmd.address, args[0])

    def close(self) -> None:
        self.osc.stop()


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
