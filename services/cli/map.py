"""``livedrummer map learn``: write a note map for a module by hitting each pad in turn.

Opens the kit like ``monitor`` does (``--midi PORT``, ``--virtual NAME`` or ``--serial DEV``)
and asks for each pad and zone in turn on stdout (:mod:`livedrummer.midi.learn`): hit it, or
press Enter to skip it (on the hi-hat pedal prompt, after moving the pedal, Enter keeps the
controller range alone), ``q`` + Enter to stop early. Then writes ``-o FILE.toml``, a note map
that ``--map FILE.toml`` loads (it is loaded back before the command says it is done). The
map's name is the file's stem.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .devices import add_api_option, kit_source
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "map", run, "learn a note map for a new module by hitting its pads")
    what = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    learn = what.add_parser(
        "learn",
        help="hit each pad in turn; write a note map",
        description="Hit each pad in turn; write a note map.",
    )
    src = learn.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="MIDI input port (name or substring)")
    src.add_argument("--virtual", metavar="NAME", help="open a virtual MIDI input port NAME")
    src.add_argument("--serial", metavar="DEV", help="serial device sending raw MIDI bytes")
    learn.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(learn)
    learn.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="FILE.toml",
        help="the note map to write",
    )
    learn.add_argument(
        "--hihat-cc",
        type=int,
        default=4,
        metavar="N",
        help="the pedal's controller number (default 4)",
    )


def run(args: argparse.Namespace) -> int:
    import select

    from livedrummer.errors import ConfigError
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.midi.learn import MapLearner
    from livedrummer.midi.notemap import load_note_map, load_note_map_file
    from livedrummer.timeline.clock import MonotonicClock

    from ..input.base import MidiSource, RawMidi

    out: Path = args.output
    if out.suffix != ".toml" or not out.stem:
        raise ConfigError(f"-o {out}: expected a NAME.toml file (NAME becomes the map's name)")
    if not out.parent.is_dir():
        raise ConfigError(f"-o {out}: folder {out.parent} does not exist")
    if not 0 <= args.hihat_cc <= 127:
        raise ConfigError(f"--hihat-cc {args.hihat_cc}: expected 0..127")
    clock = MonotonicClock()
    decoder = MessageDecoder(load_note_map("general-midi"))  # unused: only the tap is read
    source: MidiSource = kit_source(args, clock, decoder)
    learner = MapLearner(out.stem, source.name, args.hihat_cc)
    said: list[str] = []

    def heard(time_s: float, msg: RawMidi) -> None:
        line = learner.feed(msg, time_s)
        if line is not None:
            said.append(line)

    source.tap = heard
    source.open()
    asked = None
    try:
        while learner.prompt is not None:
            if learner.prompt is not asked:
                asked = learner.prompt
                print(f"hit: {asked[3]}   (Enter: skip, q: stop)", flush=True)
            source.read(0.05)
            for line in said:
                print(f"  {line}", flush=True)
            said.clear()
            ready, _, _ = select.select([sys.stdin], [], [], 0)
            if ready:
                typed = sys.stdin.readline()
                if typed == "" or typed.strip().lower() in ("q", "quit"):
                    break  # end of input, or the drummer stops early
                answer = learner.finish_pedal()
                if answer is not None:
                    print(f"  {answer}", flush=True)
                else:
                    learner.skip()
    finally:
        source.close()
    out.write_text(learner.toml())
    learned = load_note_map_file(out)  # what --map FILE.toml will read, checked now
    chokes = "seen" if learner.chokes else "not seen"
    print(
        f"wrote {out}: {len(learned.notes)} notes, pedal controller {learned.hihat_cc} "
        f"closed at {learned.hihat_cc_closed}, chokes {chokes}; use it with --map {out}"
    )
    return 0
