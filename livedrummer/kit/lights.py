"""Show lighting as scene objects: a key, a fill, a rim and a wash light, and the hall's ambient.

Why in ``kit``. A kit file, an expression preset, a stage file and a cue each carry a
``[lights]`` table, checked when the file is read; the lights are plain data, so they live
below every package that reads such a file (kit, body, stage, live) and the renderer
(:mod:`services.display.renderer`) takes them from here like any other scene data.

Why this shape. Lights are plain data in the scene (as pygfx keeps them), not uniforms
scattered through the renderer: a :class:`Light` is a colour, an intensity and a direction
(azimuth and elevation, degrees, of where the light comes *from*, seen from the kit: azimuth 0
is the audience side (+y), 90 the drummer's right (+x), 180 behind him; elevation 90 straight
above), and a :class:`LightRig` holds the four a show uses plus the ambient sky and ground
colours (an environment term, so no lit surface is ever black) and an exposure. The renderer
uploads a rig each frame (:meth:`LightRig.uniforms`), so a rig changed live (OSC
``/livedrummer/light/<name>/<param>``, a cue) is seen on the next frame.

Every colour here is linear light; the shaders work in linear light, tone-map the sum
(a fitted filmic curve) and encode sRGB once per fragment (``shaders/lighting.glsl``).

* key: the front-of-house spot; the only light that casts shadows (from
  :data:`KEY_DISTANCE_M` along its direction);
* fill: a soft, wrapped light from the other front side, filling the key's shadows;
* rim: a back light, drawn on the edges that turn away from the viewer and towards it: it
  cuts the drummer out of the dark hall;
* wash: a broad coloured light from above, lighting the stage floor's pool and every top.

:data:`LOOKS` are the themes a show picks (``--look``). A ``[lights]`` TOML table (in a kit,
stage or preset file, or a cue) is read into a :class:`LightSpec` (:func:`parse_light_spec`:
``look = NAME`` and ``[lights.key]``-style tables overriding parameters), checked when the file
is loaded and applied later over whatever rig is in force, so files layer
(:func:`resolve_lights`: ``--look`` > stage > preset > kit > the default look) and a cue
changes only what it names. A rig changes one parameter at a time (:func:`with_light_param`,
the OSC and cue path) and fades into another (:func:`blend_rigs`, driven by the live
:class:`~livedrummer.live.stage.Stage`). Limits: directional lights only (the key's position
is for its shadow); one shadowed light; no coloured shadows; a fade mixes light by light, so
a light switched on or off fades its intensity.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError

if TYPE_CHECKING:  # numpy is imported where it is used: a kit file's [lights] must not load it
    import numpy as np

#: The light names of a rig, in upload order.
LIGHT_NAMES: tuple[str, ...] = ("key", "fill", "rim", "wash")
#: A light's live parameters (OSC ``/livedrummer/light/<name>/<param>``): the intensity, the
#: direction, the linear colour (``r``, ``g``, ``b`` one at a time, or ``color`` "#rrggbb")
#: and whether it is on (``enabled``, 0 or 1).
LIGHT_PARAMS: tuple[str, ...] = (
    "intensity",
    "azimuth",
    "elevation",
    "r",
    "g",
    "b",
    "color",
    "enabled",
)
#: How far the key spot stands from the kit's centre (its shadow map's eye).
KEY_DISTANCE_M = 4.6
MAX_INTENSITY = 20.0


class LightError(ConfigError):
    """A light, theme or light parameter that does not exist or is out of range."""


@dataclass(frozen=True)
class Light:
    """One light: linear colour (0..1 each), intensity, and where it comes from (degrees)."""

    color: tuple[float, float, float]
    intensity: float
    azimuth_deg: float
    elevation_deg: float
    enabled: bool = True  # off: it adds nothing (its other settings are kept for when it is on)

    @property
    def direction(self) -> np.ndarray:
        """Unit vector from the kit towards the light (kit frame: +x right, +y audience, +z up)."""
        import numpy as np

        az, el = math.radians(self.azimuth_deg), math.radians(self.elevation_deg)
        return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])

    @property
    def radiance(self) -> tuple[float, float, float]:
        """Colour times intensity: what the shader adds per unit of cosine (0 when off)."""
        r, g, b = (c * self.intensity * self.enabled for c in self.color)
        return (r, g, b)


@dataclass(frozen=True)
class LightRig:
    """The four show lights, the ambient environment and the exposure (module docstring)."""

    key: Light
    fill: Light
    rim: Light
    wash: Light
    sky: tuple[float, float, float]  # ambient from above, linear
    ground: tuple[float, float, float]  # ambient from below (the floor's bounce), linear
    exposure: float = 1.0
    name: str = "custom"

    def light(self, name: str) -> Light:
        if name not in LIGHT_NAMES:
            raise LightError(f"light {name!r}: expected one of {', '.join(LIGHT_NAMES)}")
        light: Light = getattr(self, name)
        return light

    def uniforms(self, centre: np.ndarray) -> dict[str, Any]:
        """The shaders' light uniforms for a kit centred at ``centre`` (xyz, metres)."""
        import numpy as np

        out: dict[str, Any] = {}
        for name in LIGHT_NAMES:
            light = self.light(name)
            out[f"u_{name}_dir"] = tuple(float(v) for v in light.direction)
            out[f"u_{name}_color"] = light.radiance
        key = np.asarray(centre, float) + KEY_DISTANCE_M * self.key.direction
        out["u_key_pos"] = tuple(float(v) for v in key)
        out["u_sky"] = self.sky
        out["u_ground"] = self.ground
        out["u_exposure"] = self.exposure
        return out


def _light(rgb: tuple[float, float, float], intensity: float, az: float, el: float) -> Light:
    return Light(rgb, intensity, az, el)


#: The themes a show can pick (``--look``).
LOOKS: dict[str, LightRig] = {
    # a warm key from front left, a cool blue back light, an amber wash: a rock stage
    "concert": LightRig(
        key=_light((1.0, 0.86, 0.70), 2.6, -35.0, 42.0),
        fill=_light((0.55, 0.65, 1.0), 0.9, 55.0, 15.0),
        rim=_light((0.45, 0.62, 1.0), 3.0, 165.0, 40.0),
        wash=_light((1.0, 0.55, 0.30), 0.9, 0.0, 80.0),
        sky=(0.05, 0.05, 0.07),
        ground=(0.025, 0.02, 0.02),
        exposure=0.8,
        name="concert",
    ),
    # neutral white, soft and even: a recording session or a lesson
    "studio": LightRig(
        key=_light((1.0, 0.97, 0.93), 2.6, -30.0, 40.0),
        fill=_light((0.95, 0.97, 1.0), 1.4, 45.0, 20.0),
        rim=_light((1.0, 1.0, 1.0), 1.6, 170.0, 45.0),
        wash=_light((1.0, 1.0, 1.0), 0.8, 0.0, 85.0),
        sky=(0.10, 0.10, 0.11),
        ground=(0.05, 0.05, 0.05),
        name="studio",
    ),
    # saturated magenta and cyan from either side, a violet back light: a club
    "neon": LightRig(
        key=_light((1.0, 0.25, 0.75), 3.0, -45.0, 35.0),
        fill=_light((0.15, 0.85, 1.0), 2.0, 50.0, 20.0),
        rim=_light((0.55, 0.25, 1.0), 3.5, 180.0, 35.0),
        wash=_light((0.35, 0.15, 0.9), 0.8, 0.0, 80.0),
        sky=(0.04, 0.03, 0.07),
        ground=(0.03, 0.02, 0.04),
        name="neon",
    ),
    # a high sun and a bright sky: an open-air festival by day
    "daylight": LightRig(
        key=_light((1.0, 0.95, 0.85), 3.4, -25.0, 60.0),
        fill=_light((0.70, 0.80, 1.0), 1.2, 60.0, 25.0),
        rim=_light((1.0, 0.95, 0.90), 1.0, 170.0, 50.0),
        wash=_light((0.60, 0.75, 1.0), 1.0, 0.0, 88.0),
        sky=(0.22, 0.25, 0.32),
        ground=(0.10, 0.09, 0.08),
        name="daylight",
    ),
}
DEFAULT_LOOK = "concert"


def look_rig(name: str) -> LightRig:
    """The theme ``name`` (:data:`LOOKS`); LightError naming the choices otherwise."""
    if name not in LOOKS:
        raise LightError(f"look {name!r}: expected one of {', '.join(LOOKS)}")
    return LOOKS[name]


_HEX = re.compile(r"#(?:[0-9a-fA-F]{3}|[0-9a-fA-F]{6})")


def _colour(text: str) -> tuple[float, float, float]:
    """``#rrggbb`` or ``#rgb`` as 0..1 per channel (each digit pair over 255)."""
    if not _HEX.fullmatch(text):
        raise ValueError(f"colour {text!r}: expected #rrggbb or #rgb")
    digits = text[1:] if len(text) == 7 else "".join(c * 2 for c in text[1:])
    r, g, b = (int(digits[i : i + 2], 16) / 255 for i in (0, 2, 4))
    return (r, g, b)


def with_light_param(rig: LightRig, light: str, param: str, value: float | str) -> LightRig:
    """``rig`` with one parameter of one light changed (the OSC/cue path); LightError naming
    the light, the parameter or the allowed range."""
    old = rig.light(light)
    where = f"light {light} {param}"
    try:
        if param == "color":
            new = replace(old, color=_colour(str(value)))
        elif param == "enabled":
            if isinstance(value, str) or float(value) not in (0.0, 1.0):
                raise ValueError(f"{value!r}: expected 0 or 1 (false or true)")
            new = replace(old, enabled=bool(value))
        elif param not in LIGHT_PARAMS:
            raise ValueError(f"expected one of {', '.join(LIGHT_PARAMS)}")
        else:
            v = float(value)
            if not math.isfinite(v):
                raise ValueError(f"{value!r} is not a number")
            if param == "intensity":
                if not 0.0 <= v <= MAX_INTENSITY:
                    raise ValueError(f"{v} outside 0..{MAX_INTENSITY:g}")
                new = replace(old, intensity=v)
            elif param == "azimuth":
                new = replace(old, azimuth_deg=v)
            elif param == "elevation":
                if not -90.0 <= v <= 90.0:
                    raise ValueError(f"{v} outside -90..90")
                new = replace(old, elevation_deg=v)
            else:
                if not 0.0 <= v <= 1.0:
                    raise ValueError(f"{v} outside 0..1")
                rgb = list(old.color)
                rgb["rgb".index(param)] = v
                new = replace(old, color=(rgb[0], rgb[1], rgb[2]))
    except ValueError as exc:
        raise LightError(f"{where}: {exc}") from None
    changes: dict[str, Any] = {light: new}
    return replace(rig, **changes)


#: One change of one light: (light name, parameter of :data:`LIGHT_PARAMS`, value).
LightChange = tuple[str, str, float | str]


@dataclass(frozen=True)
class LightSpec:
    """What a ``[lights]`` table (a kit, stage, preset or cue) says, checked, not yet applied:
    a look to start from, and changes on top of it. :meth:`apply` lays it over a rig, so
    files layer (``--look`` > stage > preset > kit > the default look, :func:`resolve_lights`)
    and a cue changes what is lit now."""

    look: str | None = None
    exposure: float | None = None
    sky: tuple[float, float, float] | None = None
    ground: tuple[float, float, float] | None = None
    changes: tuple[LightChange, ...] = ()

    def apply(self, base: LightRig) -> LightRig:
        rig = look_rig(self.look) if self.look is not None else base
        rig = replace(
            rig,
            exposure=rig.exposure if self.exposure is None else self.exposure,
            sky=rig.sky if self.sky is None else self.sky,
            ground=rig.ground if self.ground is None else self.ground,
        )
        for light, param, value in self.changes:
            rig = with_light_param(rig, light, param, value)
        given = (self.exposure, self.sky, self.ground)
        custom = bool(self.changes) or any(v is not None for v in given)
        return replace(rig, name="custom" if custom else rig.name)


def parse_light_spec(table: Table) -> LightSpec:
    """A :class:`LightSpec` from a ``[lights]`` table: ``look = NAME``, ``exposure``,
    ``sky``/``ground`` ([r, g, b] linear) and per light (``[lights.key]``, fill, rim, wash)
    ``intensity``, ``azimuth``, ``elevation`` (or ``direction = [azimuth, elevation]``),
    ``color`` ("#rrggbb", or [r, g, b] linear 0..1) and ``enabled``. A bad key or value
    raises the table's error naming the file, the table and the key."""
    look = table.text("look", None, choices=LOOKS)
    exposure = table.number("exposure", None, lo=0.05, hi=16.0)
    sky = table.vector("sky", 3, None)
    ground = table.vector("ground", 3, None)
    changes: list[LightChange] = []
    for name in LIGHT_NAMES:
        if not table.has(name):
            continue
        t = table.table(name)
        for key in ("intensity", "azimuth", "elevation", "direction", "color", "enabled"):
            if not t.has(key):
                continue
            found: list[LightChange] = []
            if key == "direction":
                az, el = t.vector(key, 2)
                found = [(name, "azimuth", az), (name, "elevation", el)]
            elif key == "enabled":
                found = [(name, key, float(t.boolean(key)))]
            elif key == "color" and not isinstance(t.raw(key), str):
                rgb = t.vector(key, 3)
                found = [(name, c, v) for c, v in zip("rgb", rgb, strict=True)]
            else:
                value = t.text(key) if key == "color" else t.number(key)
                found = [(name, key, value)]
            for change in found:
                try:
                    with_light_param(LOOKS[DEFAULT_LOOK], *change)
                except LightError as exc:
                    raise t.fail(key, str(exc).split(": ", 1)[1]) from None  # names the value
            changes.extend(found)
        t.done()
    table.done()
    return LightSpec(look, exposure, sky, ground, tuple(changes))


def parse_lights(table: Table, base: LightRig | None = None) -> LightRig:
    """A rig from a ``[lights]`` table (:func:`parse_light_spec`) laid over ``base`` (else
    the default look)."""
    return parse_light_spec(table).apply(base if base is not None else LOOKS[DEFAULT_LOOK])


def light_spec_of(data: dict[str, Any], source: str, error: type[ConfigError]) -> LightSpec | None:
    """The ``[lights]`` table of a parsed TOML file (a kit, stage or preset), checked; None
    when it has none."""
    if "lights" not in data:
        return None
    return parse_light_spec(Table(data["lights"], source, "lights", error))


def resolve_lights(look: str | None, *specs: LightSpec | None) -> LightRig:
    """The rig a show starts with: the default look, each file's ``[lights]`` over it from
    the weakest to the strongest (kit, preset, stage), and a ``--look`` given on the command
    line over all (it names the whole theme: the files' changes are dropped)."""
    if look is not None:
        return look_rig(look)
    rig = LOOKS[DEFAULT_LOOK]
    for spec in specs:
        if spec is not None:
            rig = spec.apply(rig)
    return rig


def _mix(a: float, b: float, s: float) -> float:
    return a + (b - a) * s


def _mix3(
    a: tuple[float, float, float], b: tuple[float, float, float], s: float
) -> tuple[float, float, float]:
    return (_mix(a[0], b[0], s), _mix(a[1], b[1], s), _mix(a[2], b[2], s))


def blend_rigs(a: LightRig, b: LightRig, s: float) -> LightRig:
    """The rig ``s`` (0..1) of the way from ``a`` to ``b`` (a light fade): colours,
    intensities, exposure and ambient mixed linearly, directions the short way round; a
    light switched on or off fades its intensity from or to 0. ``s`` >= 1 gives ``b``."""
    if s >= 1.0:
        return b
    if s <= 0.0:
        return a
    lights: dict[str, Any] = {}
    for name in LIGHT_NAMES:
        la, lb = a.light(name), b.light(name)
        turn = (lb.azimuth_deg - la.azimuth_deg + 180.0) % 360.0 - 180.0
        lights[name] = Light(
            color=_mix3(la.color, lb.color, s),
            intensity=_mix(la.intensity * la.enabled, lb.intensity * lb.enabled, s),
            azimuth_deg=la.azimuth_deg + turn * s,
            elevation_deg=_mix(la.elevation_deg, lb.elevation_deg, s),
        )
    return LightRig(
        sky=_mix3(a.sky, b.sky, s),
        ground=_mix3(a.ground, b.ground, s),
        exposure=_mix(a.exposure, b.exposure, s),
        name=b.name,
        **lights,
    )


def load_lights(path: Path | str, base: LightRig | None = None) -> LightRig:
    """The ``[lights]`` table of a TOML file (a kit, stage or lights file)."""
    data = read_toml(Path(path), LightError)
    return parse_lights(Table(data.get("lights", {}), str(path), "lights", LightError), base)
