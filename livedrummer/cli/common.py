"""Small helpers shared by subcommands: option definitions and the bundled demo groove."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from livedrummer.resources import data_dir

Subparsers = Any  # argparse's _SubParsersAction is private; its type is not worth importing
Command = Callable[[argparse.Namespace], int]

DEMO_GROOVE = "grooves/gmd-drummer1-funk-80.mid"
DEMO_MAP = "roland-td"


def has_screen() -> bool:
    """A graphical session to open a window on (X11 or Wayland)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def demo_groove() -> Path:
    """The bundled demo groove (Groove MIDI Dataset, CC BY 4.0; see kits/grooves)."""
    return data_dir("kits") / DEMO_GROOVE


def add_command(sub: Subparsers, name: str, func: Command, help_: str) -> argparse.ArgumentParser:
    parser: argparse.ArgumentParser = sub.add_parser(name, help=help_, description=help_)
    parser.set_defaults(func=func)
    return parser


def add_map_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--map", default="general-midi", help="note map name or .toml path (default general-midi)"
    )


def add_kit_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--kit", default="rock5", help="kit name or .toml path (default rock5)")


def add_motion_options(p: argparse.ArgumentParser) -> None:
    """``--sticking``, ``--strokes``, ``--preset``: how the body is animated (check, export...)."""
    p.add_argument("--preset", default=None, help="expression preset name or .toml path")
    p.add_argument(
        "--sticking",
        default="optimal",
        help="limb assignment: a livedrummer.sticking strategy (default optimal) or fallback",
    )
    p.add_argument(
        "--strokes",
        default="livedrummer",
        choices=("livedrummer", "paper", "smed"),
        help="stroke overlap rules (default livedrummer)",
    )
