"""``livedrummer ports``: the MIDI input ports the input daemon can open (ALSA or JACK)."""

from __future__ import annotations

import argparse

from livedrummer.cli.common import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "ports", run, "list MIDI input ports (for livedrummer input --midi)")
    p.add_argument("--api", choices=("default", "alsa", "jack"), default="default",
                   help="MIDI system to ask (default: rtmidi's choice)")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    from services.input.midiport import list_ports

    ports = list_ports(args.api)
    if not ports:
        print(f"no MIDI input ports ({args.api})")
    for i, name in enumerate(ports):
        print(f"{i}: {name}")
    return 0
