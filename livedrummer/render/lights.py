"""The show lights, under the name the drawing side imports them by.

The light model (lights, rigs, looks, ``[lights]`` tables, fades) is
:mod:`livedrummer.kit.lights`: the kit, preset and stage loaders read a ``[lights]`` table
there, below this package. The renderer and its passes, the exports and the look bench take
a rig from this module, which only names those objects again, so the drawing code has one
place to import scene data from (``livedrummer.render``) and the model has one definition.
"""

from __future__ import annotations

from livedrummer.kit.lights import (
    DEFAULT_LOOK,
    KEY_DISTANCE_M,
    LIGHT_NAMES,
    LOOKS,
    Light,
    LightError,
    LightRig,
    look_rig,
    parse_lights,
    with_light_param,
)

__all__ = [
    "DEFAULT_LOOK",
    "KEY_DISTANCE_M",
    "LIGHT_NAMES",
    "LOOKS",
    "Light",
    "LightError",
    "LightRig",
    "look_rig",
    "parse_lights",
    "with_light_param",
]
