"""The window's readout: where the file is, how it plays, which camera, and the key help.

A person at the stage computer needs to see at a glance what the window is doing: the
position and length (``0:12.4 / 1:28.5``), the speed, paused or playing (or reversed), the
camera, a clear line when the file has ended, and, on H, every key. :func:`hud_lines` makes
those lines from plain values; :func:`hud_image` paints them with the 5x7 font
(:mod:`livedrummer.render.font5x7`) white on a translucent dark panel, an RGBA image the
renderer blends over the frame (``Renderer.draw_overlay``), so the readout costs one small
texture upload when its text changes and nothing when it does not.

Limits: upper-case ASCII only (the font's); a fixed corner (top left); the live window shows
its own state line (waiting, playing, stalled) through the same functions.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from livedrummer.midi.keypads import help_lines as keypad_help
from livedrummer.render.font5x7 import GLYPH_H, text_size
from livedrummer.render.overlay_raster import draw_text

#: What H shows, one key per line (the window's keys, :mod:`services.display.window`).
HELP_LINES: tuple[str, ...] = (
    "SPACE  PLAY / PAUSE",
    "LEFT RIGHT  STEP     SHIFT  SEEK 5 S",
    "HOME END  START / END     R  REVERSE",
    "+ -  SPEED     0  NORMAL SPEED",
    "M  MARK     [ ]  PREVIOUS / NEXT MARK",
    "A B  LOOP FROM A TO B     L  NO LOOP     S  STEP SIZE",
    "1-8  CAMERAS     O  SCORE     G  JOINT ANGLES",
    "SHIFT 1-8  STORE A VIEW (1-8 RECALLS IT)",
    "DRAG  TURN     RIGHT DRAG  MOVE     WHEEL  ZOOM",
    "F  FULL SCREEN     I  READOUT     H  HELP     Q ESC  QUIT",
    *keypad_help(),
)
PANEL_RGBA = (10, 10, 16, 170)
TEXT_RGBA = (235, 235, 235, 255)
PAD = 6


def clock_text(seconds: float) -> str:
    seconds = max(0.0, seconds)
    minutes = int(seconds // 60)
    return f"{minutes}:{seconds - 60 * minutes:04.1f}"


def hud_lines(
    position_s: float,
    duration_s: float,
    speed: float,
    playing: bool,
    reverse: bool,
    camera: str,
    show_help: bool = False,
    loop: tuple[float, float] | None = None,
    step_s: float | None = None,
) -> list[str]:
    """The readout for a file window (see the module docstring); ``loop`` and ``step_s``
    add the loop's ends and the step size."""
    state = ("REVERSE" if reverse else "PLAYING") if playing else "PAUSED"
    lines = [
        f"{clock_text(position_s)} / {clock_text(duration_s)}   {speed:g}X   {state}   "
        f"CAMERA {camera.upper()}   H HELP"
    ]
    extra = []
    if loop is not None:
        extra.append(f"LOOP {clock_text(loop[0])} - {clock_text(loop[1])}")
    if step_s is not None:
        extra.append(f"STEP {step_s * 1000:.0f} MS")
    if extra:
        lines.append("   ".join(extra))
    if not playing and position_s >= duration_s - 1e-6:
        lines.append("END OF FILE - HOME TO PLAY AGAIN, Q TO QUIT")
    if show_help:
        lines += ["", *HELP_LINES]
    return lines


def live_lines(state: str, camera: str, show_help: bool = False, keys: bool = True) -> list[str]:
    """The readout for a live window: the performer's state and the camera; ``keys``: the
    help lists the drum keys (they play into an input port)."""
    lines = [f"LIVE   {state.upper()}   CAMERA {camera.upper()}   H HELP"]
    if show_help:
        lines += ["", "1-8  CAMERAS     SHIFT 1-8  STORE A VIEW",
                  "DRAG  TURN     RIGHT DRAG  MOVE     WHEEL  ZOOM",
                  "O  SCORE     G  JOINT ANGLES",
                  "F  FULL SCREEN     I  READOUT     Q ESC  QUIT"]  # fmt: skip
        lines += keypad_help() if keys else []
    return lines


def hud_image(lines: Sequence[str], scale: int = 2) -> np.ndarray:
    """``lines`` painted on a translucent panel: (h, w, 4) uint8, straight alpha, top row first."""
    line_h = (GLYPH_H + 3) * scale
    width = max((text_size(line, scale)[1] for line in lines), default=0) + 2 * PAD
    height = len(lines) * line_h + 2 * PAD - 3 * scale
    img = np.empty((max(height, 1), max(width, 1), 4), np.uint8)
    img[:] = PANEL_RGBA
    for i, line in enumerate(lines):
        draw_text(img, line, PAD + i * line_h, PAD, scale, TEXT_RGBA)
    return img
