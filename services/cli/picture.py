"""What the picture looks like: ``--background``, ``--look`` (the show lights) and ``--aa``,
checked before any GL context is made (one line on a bad value). Imports nothing heavy at
module level.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from livedrummer.render.background import Background


def add_background_option(parser: Any, transparent: bool = True) -> None:
    """``--background COLOUR|IMAGE|chroma|transparent``: what is behind the stage
    (:mod:`livedrummer.render.background`); a window cannot be ``transparent``."""
    kinds = (
        "#rrggbb, an image file, chroma or transparent"
        if transparent
        else ("#rrggbb, an image file or chroma")
    )
    parser.add_argument(
        "--background",
        metavar="COLOUR|IMAGE|chroma" + ("|transparent" if transparent else ""),
        help=f"behind the stage: {kinds} (default: the dark hall)",
    )


def add_look_option(parser: Any) -> None:
    """``--look NAME``: the show lights' theme (:data:`livedrummer.kit.lights.LOOKS`)."""
    from livedrummer.kit.lights import DEFAULT_LOOK, LOOKS

    parser.add_argument(
        "--look",
        choices=tuple(LOOKS),
        default=None,
        help="the show lights' theme, over the [lights] of the stage, preset "
        f"and kit files (default: theirs, else {DEFAULT_LOOK})",
    )


def lights_of(args: argparse.Namespace, kit: Any, stage: Any = None) -> Any:
    """The show lights a command starts with (:func:`livedrummer.kit.lights.resolve_lights`):
    ``--look`` over the stage file's ``[lights]``, over the ``--preset``'s, over the kit's,
    over the default look. ``stage``: a loaded stage file (``--stage``), or None."""
    from livedrummer.body.expression import preset_lights
    from livedrummer.kit.lights import resolve_lights

    preset = getattr(args, "preset", None)
    return resolve_lights(
        getattr(args, "look", None),
        getattr(kit, "lights", None),
        preset_lights(preset) if preset else None,
        getattr(stage, "lights", None),
    )


def background_of(args: argparse.Namespace, window: bool = False) -> Background:
    """The checked, decoded ``--background`` of ``args`` (one line on a bad value)."""
    from livedrummer.render.background import BackgroundError

    from ..display.background import load_background

    bg = load_background(args.background)
    if window and bg.transparent:
        raise BackgroundError(
            "--background transparent: a window shows no alpha; render PNG frames or a "
            ".mov/.webm video with `livedrummer render --background transparent`"
        )
    return bg


def lights_argv(args: argparse.Namespace) -> list[str]:
    """What a child display needs to start from the same lights (:func:`lights_of`) as this
    command: ``--look`` and the ``--preset`` (for its ``[lights]``), as given."""
    out = ["--look", args.look] if getattr(args, "look", None) else []
    preset = getattr(args, "preset", None)
    return out + (["--preset", str(preset)] if preset is not None else [])


#: Multisample counts a GL context accepts (powers of two; Mesa's llvmpipe offers up to 8).
AA_SAMPLES = (0, 1, 2, 4, 8, 16)


def check_aa(samples: int) -> None:
    """``--aa N``: one line naming the counts allowed, before any GL context is made."""
    from livedrummer.errors import ConfigError

    if samples not in AA_SAMPLES:
        allowed = ", ".join(str(n) for n in AA_SAMPLES)
        raise ConfigError(f"--aa {samples}: expected one of {allowed} (0: no multisampling)")


def parse_aa(text: str) -> tuple[int, bool]:
    """``--aa fxaa|N`` of ``render``: (multisample count, FXAA pass), one line when bad."""
    from livedrummer.errors import ConfigError

    value = str(text).strip().lower()
    if value == "fxaa":
        return 0, True
    if not value.isdigit():
        allowed = ", ".join(str(n) for n in AA_SAMPLES)
        raise ConfigError(f"--aa {text}: expected fxaa or one of {allowed}")
    check_aa(int(value))
    return int(value), False
