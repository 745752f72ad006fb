"""``livedrummer ports``: the MIDI input ports the input daemon can open (ALSA or JACK)."""

from __future__ import annotations

import argparse

from .devices import add_api_option
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "ports", run, "list MIDI input ports (for livedrummer input --midi)")
    add_api_option(p)


def run(args: argparse.Namespace) -> int:
    from ..input.midiport import list_ports_by_api

    ports = list_ports_by_api(args.api)
    if not ports:
        print(f"no MIDI input ports ({args.api})")
    for i, (system, name) in enumerate(ports):
        print(f"{i}: {name}  [{system}]")
    return 0
