"""What the audience sees besides the drummer: the camera, the blackout and the show lights,
set while playing.

Why this shape. A show technician cues camera moves and blackouts (over OSC, a MIDI
controller or a cue list); the display applies them on its own frame clock. This module is
the pure state of those two: :class:`Stage` takes commands stamped with the display's clock
time and answers, for any frame time, the camera to draw from (a smooth move between stored
viewpoints, :class:`~livedrummer.render.camera.CameraMove`, or a cut) and how dark the frame
is (0 picture .. 1 black; a blackout fades in and out over ``fade_s`` along a smoothstep),
and the light rig to draw with (:meth:`Stage.lights_at`: a light change, an OSC
``/livedrummer/light/...`` or a cue's, fades over its own time from the rig as it is, along
the same smoothstep; :func:`~livedrummer.kit.lights.blend_rigs`). It holds no socket and
no GL: the display service feeds it and reads it each frame.

Limits: one move and one light fade at a time (a new one starts from where the camera or the
lights are); the blackout's fade is the same length both ways.
"""

from __future__ import annotations

from livedrummer.kit.lights import DEFAULT_LOOK, LightRig, blend_rigs, look_rig
from livedrummer.kit.model import Kit
from livedrummer.render.camera import CAMERA_NAMES, Camera, CameraMove, kit_cameras


def camera_name(spec: str | float) -> str:
    """A camera given by name or by its number 1..8 (the window's keys); ValueError naming
    the choices otherwise."""
    if isinstance(spec, str) and spec in CAMERA_NAMES:
        return spec
    try:
        number = float(spec)
    except ValueError:
        number = 0.0
    if number.is_integer() and 1 <= number <= len(CAMERA_NAMES):
        return CAMERA_NAMES[int(number) - 1]
    raise ValueError(f"camera {spec!r}: expected one of {', '.join(CAMERA_NAMES)} or 1-8")


def _smoothstep(x: float) -> float:
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x)


class Stage:
    """The camera and the blackout (see the module docstring)."""

    def __init__(
        self,
        kit: Kit,
        camera: str = "stage",
        fade_s: float = 0.5,
        move_s: float = 1.2,
        lights: LightRig | None = None,
    ) -> None:
        self.cameras = kit_cameras(kit)
        #: the rig the lights are at or fading to (the last change's); lights_at for a frame
        self.lights = lights if lights is not None else look_rig(DEFAULT_LOOK)
        self._lights_from = self.lights
        self._lights_t0 = -1e300
        self._lights_fade_s = 0.0
        self.fade_s = fade_s
        self.move_s = move_s
        start = self.cameras[camera_name(camera)]
        self._move = CameraMove(start, start, 0.0, 0.0)
        self.camera = start.name
        self.blackout = False
        self._fade_from = 0.0  # darkness when the last fade began
        self._fade_t0 = -1e300

    def set_camera(self, spec: str | float, now_s: float, cut: bool = False) -> None:
        """Move (or ``cut``) to a stored viewpoint, by name or number 1..8."""
        end = self.cameras[camera_name(spec)]
        self._move = CameraMove(self._move.at(now_s), end, now_s, 0.0 if cut else self.move_s)
        self.camera = end.name

    def set_blackout(self, on: bool, now_s: float) -> None:
        """Fade to black (``on``) or back to the picture, from where the fade is now."""
        if on == self.blackout:
            return
        self._fade_from = self.darkness(now_s)
        self._fade_t0 = now_s
        self.blackout = on

    def set_lights(self, rig: LightRig, now_s: float, fade_s: float = 0.0) -> None:
        """Change the lights to ``rig``, fading over ``fade_s`` from where they are now."""
        self._lights_from = self.lights_at(now_s)
        self._lights_t0 = now_s
        self._lights_fade_s = max(0.0, fade_s)
        self.lights = rig

    def lights_at(self, now_s: float) -> LightRig:
        """The light rig to draw a frame at ``now_s`` with."""
        if self._lights_fade_s <= 0.0 or now_s >= self._lights_t0 + self._lights_fade_s:
            return self.lights if now_s >= self._lights_t0 else self._lights_from
        s = _smoothstep((now_s - self._lights_t0) / self._lights_fade_s)
        return blend_rigs(self._lights_from, self.lights, s)

    def view(self, now_s: float) -> Camera:
        """The camera to draw a frame at ``now_s`` from."""
        return self._move.at(now_s)

    def darkness(self, now_s: float) -> float:
        """0: the picture as drawn; 1: black."""
        goal = 1.0 if self.blackout else 0.0
        if self.fade_s <= 0:
            return goal
        s = _smoothstep((now_s - self._fade_t0) / self.fade_s)
        return goal if s >= 1.0 else self._fade_from + (goal - self._fade_from) * s
