"""``livedrummer control learn``: map a MIDI controller to the show, one control at a time.

Opens the controller like ``map learn`` opens a kit (``--midi PORT`` or ``--virtual NAME``)
and loops: move a fader or knob, or hit a pad; the command names what it heard (``cc 7 on
channel 1``) and asks for its target on stdin, one of ``param NAME``, ``camera NAME|1-8``,
``cut NAME|1-8``, ``cue NAME``, ``preset NAME`` or ``blackout`` (``skip`` leaves the control
out); a wrong answer is one line saying what is expected, and the question again. An empty
line (or the end of stdin) at the "move a control" prompt finishes: ``-o FILE.toml`` is
written (:mod:`livedrummer.live.controlmap`), loaded back to check it, and ``up --control
FILE.toml --control-midi PORT`` applies it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .devices import add_api_option
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "control", _usage)
    what = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    learn = what.add_parser(
        "learn",
        help="move each control, name its target; write a map",
        description="Move each control, name its target; write a map.",
    )
    src = learn.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="the controller's MIDI port")
    src.add_argument("--virtual", metavar="NAME", help="open a virtual MIDI input port NAME")
    add_api_option(learn)
    learn.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        metavar="FILE.toml",
        help="the control map to write",
    )
    learn.set_defaults(func=run_learn)


def _usage(args: argparse.Namespace) -> int:  # unreachable: ACTION is required
    return 2


def _read_line() -> str | None:
    line = sys.stdin.readline()
    return None if line == "" else line.strip()


def run_learn(args: argparse.Namespace) -> int:
    import select

    from livedrummer.errors import ConfigError
    from livedrummer.live.controlmap import (
        TARGETS,
        Binding,
        ControlMap,
        check_target,
        load_control_map,
    )
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.clock import MonotonicClock

    from ..input.base import RawMidi
    from ..input.midiport import MidiPortSource

    out: Path = args.output
    if out.suffix != ".toml" or not out.parent.is_dir():
        raise ConfigError(f"-o {out}: expected FILE.toml in a folder that exists")
    heard: list[RawMidi] = []

    def tap(_time_s: float, msg: RawMidi) -> None:
        if msg.type == "control_change" or (msg.type == "note_on" and msg.velocity > 0):
            heard.append(msg)

    decoder = MessageDecoder(load_note_map("general-midi"))  # unused: only the tap is read
    virtual = args.virtual is not None
    source = MidiPortSource(
        args.virtual or args.midi, MonotonicClock(), decoder, api=args.api, virtual=virtual
    )
    if not virtual:
        source.check()
    source.tap = tap
    source.open()
    bindings: list[Binding] = []
    taken: set[tuple[str, int, int]] = set()
    choices = " | ".join(f"{t} {'' if t == 'blackout' else 'X'}".strip() for t in TARGETS)
    try:
        while True:
            print("move a control (fader, knob or pad); Enter: done", flush=True)
            heard.clear()
            msg = None
            while msg is None:
                source.read(0.05)
                fresh = [m for m in heard if _key(m) not in taken]
                if fresh:
                    msg = fresh[0]
                    break
                ready, _, _ = select.select([sys.stdin], [], [], 0)
                if ready and not _read_line():
                    break
            if msg is None:
                break
            kind, number = _key(msg)[:2]
            print(
                f"heard {kind} {number} on channel {msg.channel + 1}: target? ({choices} | skip)",
                flush=True,
            )
            while True:
                answer = _read_line()
                if answer is None or answer == "skip":
                    print(f"  {kind} {number} left out", flush=True)
                    break
                target, _, value = answer.partition(" ")
                try:
                    value = check_target(target, value.strip(), kind)
                except ValueError as exc:
                    print(f"  {exc}; again:", flush=True)
                    continue
                bindings.append(Binding(kind, number, msg.channel, target, value))
                print(f"  {kind} {number} -> {target} {value}".rstrip(), flush=True)
                break
            taken.add(_key(msg))
            if answer is None:
                break
    finally:
        source.close()
    out.write_text(ControlMap(bindings).toml())
    learned = load_control_map(out)  # what up --control reads, checked now
    print(
        f"wrote {out}: {len(learned.bindings)} controls; use it with "
        f"up --control {out} --control-midi PORT"
    )
    return 0


def _key(msg: object) -> tuple[str, int, int]:
    """(kind, number, channel) of a controller or pad message."""
    kind = "cc" if getattr(msg, "type", "") == "control_change" else "note"
    number = getattr(msg, "control" if kind == "cc" else "note", 0)
    return kind, int(number), int(getattr(msg, "channel", 0))
