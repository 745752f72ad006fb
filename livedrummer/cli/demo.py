"""``livedrummer demo``: the main job on the bundled groove; grows with the pipeline."""

from __future__ import annotations

import argparse

from livedrummer.cli.common import DEMO_MAP, Subparsers, add_command, demo_groove
from livedrummer.cli.inspect import print_summary
from livedrummer.midifile import read_midi_file
from livedrummer.notemap import load_note_map


def register(sub: Subparsers) -> None:
    add_command(sub, "demo", run, "run the pipeline on the bundled demo groove")


def run(args: argparse.Namespace) -> int:
    groove = demo_groove()
    print(f"demo: {groove.name} (Groove MIDI Dataset, CC BY 4.0)")
    print_summary(read_midi_file(groove, load_note_map(DEMO_MAP)).summary())
    return 0
