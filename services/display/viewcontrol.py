"""The mouse and the viewpoint keys of a window: orbit, zoom, pan; Shift+1..8 stores, 1..8 recalls.

Both windows (the file window, :mod:`.window`, and the live one, :mod:`.surface`) hold their
camera as a :class:`~livedrummer.render.camera.CameraMove` and hand it to a :class:`ViewControl`
with each key and once a frame; the control answers with the move to use from then on. The
maths is :mod:`livedrummer.render.orbit` (pure); this module only installs the GLFW mouse
callbacks, gathers what the mouse did since the last frame, and keeps the user's
:class:`~livedrummer.render.orbit.Viewpoints` in ``$LIVEDRUMMER_HOME/viewpoints.json``, saved
at every store so a crash loses nothing.

Left drag orbits, right or middle drag pans, the wheel zooms. Number keys: a stored viewpoint
wins over the built-in camera of the same number (Shift+N over N: store, then N recalls it); a
mouse move stops a camera glide where it is. A viewpoints file that cannot be read is logged
once and the window starts with none stored (it is rewritten at the next store).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from livedrummer.render.camera import CAMERA_NAMES, Camera, CameraMove
from livedrummer.render.orbit import FILE_NAME, ViewpointError, Viewpoints, orbit, pan, zoom
from livedrummer.resources import user_home

log = logging.getLogger("livedrummer.display")


def viewpoints_path() -> Path:
    return user_home() / FILE_NAME


class ViewControl:
    """Mouse and viewpoint-key state of one GLFW window (see the module docstring)."""

    def __init__(self, glfw: Any, window: Any, path: Path | None = None) -> None:
        self.path = viewpoints_path() if path is None else path
        try:
            self.viewpoints = Viewpoints.load(self.path)
        except ViewpointError as exc:
            log.warning("%s; starting with no stored viewpoints", exc)
            self.viewpoints = Viewpoints()
        self._glfw = glfw
        self._button: int | None = None
        self._last: tuple[float, float] | None = None
        self._orbit = [0.0, 0.0]
        self._pan = [0.0, 0.0]
        self._zoom = 0.0

        # The cursor is followed from its own events, not asked for at a press: X11 answers
        # that question with where the pointer is now, after events still queued.
        def on_button(_w: Any, button: int, action: int, _mods: int) -> None:
            if action == glfw.PRESS:
                self._button = button
            elif action == glfw.RELEASE and button == self._button:
                self._button = None

        def on_cursor(_w: Any, x: float, y: float) -> None:
            last, self._last = self._last, (x, y)
            if self._button is None or last is None:
                return
            acc = self._orbit if self._button == glfw.MOUSE_BUTTON_LEFT else self._pan
            acc[0] += x - last[0]
            acc[1] += y - last[1]

        def on_scroll(_w: Any, _dx: float, dy: float) -> None:
            self._zoom += dy

        glfw.set_mouse_button_callback(window, on_button)
        glfw.set_cursor_pos_callback(window, on_cursor)
        glfw.set_scroll_callback(window, on_scroll)

    def key(
        self, name: str, move: CameraMove, cameras: dict[str, Camera], now: float
    ) -> tuple[CameraMove, str | None]:
        """The move after key ``name`` and the camera's new label (None: not a view key)."""
        digit = name.removeprefix("shift+")
        if not (digit.isdigit() and 1 <= int(digit) <= len(CAMERA_NAMES)):
            return move, None
        slot = int(digit)
        here = move.at(now)
        if name.startswith("shift+"):
            self.viewpoints.store(slot, here)
            try:
                self.viewpoints.save(self.path)
            except OSError as exc:
                log.warning("viewpoint %d: cannot save %s (%s)", slot, self.path, exc.strerror)
            log.info("viewpoint %d stored", slot)
            return move, f"view {slot}"
        stored = self.viewpoints.recall(slot)
        if stored is not None:
            return CameraMove(here, stored, now), f"view {slot}"
        return CameraMove(here, cameras[CAMERA_NAMES[slot - 1]], now), CAMERA_NAMES[slot - 1]

    def mouse(self, move: CameraMove, now: float, size: tuple[int, int]) -> CameraMove:
        """The move after what the mouse did since the last call (``move`` if nothing)."""
        if self._orbit == [0.0, 0.0] and self._pan == [0.0, 0.0] and self._zoom == 0.0:
            return move
        cam = move.at(now)
        height = size[1]
        if self._orbit != [0.0, 0.0]:
            cam = orbit(cam, self._orbit[0], self._orbit[1], height)
        if self._pan != [0.0, 0.0]:
            cam = pan(cam, self._pan[0], self._pan[1], height)
        if self._zoom:
            cam = zoom(cam, self._zoom)
        self._orbit, self._pan, self._zoom = [0.0, 0.0], [0.0, 0.0], 0.0
        return CameraMove(cam, cam, now, 0.0)
