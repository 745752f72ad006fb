"""Show lighting as scene objects: a key, a fill, a rim and a wash light, and the hall's ambient.

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

:data:`LOOKS` are the themes a show picks (``--look``); a rig can also be read from a TOML
table (:func:`parse_lights`: ``[lights]`` with ``look = NAME`` and ``[lights.key]``-style
tables overriding parameters) and changed one parameter at a time (:func:`with_light_param`:
the OSC and cue path). Limits: directional lights only (the key's position is for its shadow);
one shadowed light; no coloured shadows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError

#: The light names of a rig, in upload order.
LIGHT_NAMES: tuple[str, ...] = ("key", "fill", "rim", "wash")
#: A light's live parameters (OSC ``/livedrummer/light/<name>/<param>``): the intensity, the
#: direction, and the linear colour (``r``, ``g``, ``b`` one at a time, or ``color`` "#rrggbb").
LIGHT_PARAMS: tuple[str, ...] = ("intensity", "azimuth", "elevation", "r", "g", "b", "color")
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

    @property
    def direction(self) -> np.ndarray:
        """Unit vector from the kit towards the light (kit frame: +x right, +y audience, +z up)."""
        az, el = math.radians(self.azimuth_deg), math.radians(self.elevation_deg)
        return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])

    @property
    def radiance(self) -> tuple[float, float, float]:
        """Colour times intensity: what the shader adds per unit of cosine."""
        r, g, b = (c * self.intensity for c in self.color)
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


def _colour(text: str) -> tuple[float, float, float]:
    from livedrummer.render.background import BackgroundError, parse_colour

    try:
        return parse_colour(text)
    except BackgroundError:
        raise ValueError(f"colour {text!r}: expected #rrggbb or #rgb") from None


def with_light_param(rig: LightRig, light: str, param: str, value: float | str) -> LightRig:
    """``rig`` with one parameter of one light changed (the OSC/cue path); LightError naming
    the light, the parameter or the allowed range."""
    old = rig.light(light)
    where = f"light {light} {param}"
    try:
        if param == "color":
            new = replace(old, color=_colour(str(value)))
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


def parse_lights(table: Table, base: LightRig | None = None) -> LightRig:
    """A rig from a ``[lights]`` table: ``look = NAME`` (else ``base``, else the default
    look), ``exposure``, ``sky``/``ground`` ([r, g, b] linear) and per light a table of
    ``intensity``, ``azimuth``, ``elevation`` and ``color`` ("#rrggbb")."""
    rig = base if base is not None else LOOKS[DEFAULT_LOOK]
    if table.has("look"):
        rig = LOOKS[table.text("look", choices=LOOKS)]
    exposure = table.number("exposure", rig.exposure, lo=0.05, hi=16.0)
    sky = table.vector("sky", 3, rig.sky)
    ground = table.vector("ground", 3, rig.ground)
    rig = replace(rig, exposure=exposure, sky=sky, ground=ground)
    for name in LIGHT_NAMES:
        if not table.has(name):
            continue
        t = table.table(name)
        for param in ("intensity", "azimuth", "elevation", "color"):
            if not t.has(param):
                continue
            value = t.text(param) if param == "color" else t.number(param)
            try:
                rig = with_light_param(rig, name, param, value)
            except LightError as exc:
                raise t.fail(param, str(exc).split(": ", 1)[1], value) from None
        t.done()
    table.done()
    return replace(rig, name=rig.name if rig.name in LOOKS else "custom")


def load_lights(path: Path | str, base: LightRig | None = None) -> LightRig:
    """The ``[lights]`` table of a TOML file (a kit, stage or lights file)."""
    data = read_toml(Path(path), LightError)
    return parse_lights(Table(data.get("lights", {}), str(path), "lights", LightError), base)
