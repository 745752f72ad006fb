"""A live kit's source and the screen: ``--midi``/``--virtual``/``--serial``, ``--api``.

The commands that listen to a kit (``monitor``, ``map learn``, ``calibrate``, ``up``) open it
through :func:`kit_source`, checked before anything starts. Imports nothing heavy at module
level.
"""

from __future__ import annotations

import argparse
import os
from typing import Any


def has_screen() -> bool:
    """A graphical session to open a window on (X11 or Wayland)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def add_api_option(parser: argparse.ArgumentParser) -> None:
    """``--api``: which MIDI system to find ``--midi`` ports on (services.input.midiport)."""
    parser.add_argument(
        "--api",
        choices=("auto", "jack", "alsa"),
        default="auto",
        help="MIDI system of --midi: jack, alsa, or auto (default: the one the "
        "port is on, ALSA first when both have it)",
    )


def kit_source(args: argparse.Namespace, clock: Any, decoder: Any) -> Any:
    """The ``--midi PORT | --virtual NAME | --serial DEV`` source (a
    ``services.input.base.MidiSource``) of ``monitor``, ``map learn``, ``calibrate`` and
    ``up``'s check before it starts anything; checked unless ``--wait``: a device that is not
    there is one line naming what is."""
    from livedrummer.errors import ConfigError

    if args.serial is not None:
        from ..input.serialport import BAUD_RATES, SerialSource

        if args.baud not in BAUD_RATES:
            raise ConfigError(f"--baud: expected one of {BAUD_RATES} (got {args.baud})")
        source: Any = SerialSource(args.serial, clock, decoder, args.baud)
    else:
        from ..input.midiport import MidiPortSource

        virtual = getattr(args, "virtual", None)  # up has no --virtual
        source = MidiPortSource(
            virtual or args.midi, clock, decoder, api=args.api, virtual=virtual is not None
        )
    if not getattr(args, "wait", False):
        source.check()
    return source
