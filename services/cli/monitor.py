"""``livedrummer monitor``: see what a kit sends, message by message, and what it means.

Opens a MIDI port (``--midi``), a virtual port (``--virtual``) or a serial trigger board
(``--serial``) like ``livedrummer input`` does (same sources, same driver stamps), but
publishes nothing and journals nothing: every channel message is printed as it arrives, with
its time since the monitor started, channel, note or controller, velocity or value, and its
meaning under ``--map`` (:mod:`livedrummer.midi.describe`): piece and zone, unknown notes
marked ``?``, the hi-hat pedal's openness, aftertouch chokes. ``--json`` prints one object per
line instead. A port that is not there is one line naming what exists (exit 2), as for
``input``; a device lost while monitoring is waited for, with a status line every 5 s. At the
end (Ctrl-C, or ``--seconds``) a summary line counts messages and unknown notes.
"""

from __future__ import annotations

import argparse
import json
import sys

from .devices import add_api_option, kit_source
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "monitor", run, "print what a kit sends and what each message means")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="MIDI input port (name or substring)")
    src.add_argument("--virtual", metavar="NAME", help="open a virtual MIDI input port NAME")
    src.add_argument("--serial", metavar="DEV", help="serial device sending raw MIDI bytes")
    p.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(p)
    p.add_argument(
        "--map", default="roland-td", help="note map name or .toml path (default roland-td)"
    )
    p.add_argument("--json", action="store_true", help="one JSON object per message")
    p.add_argument(
        "--seconds", type=float, metavar="S", help="stop after S seconds (default: at Ctrl-C)"
    )
    p.add_argument(
        "--wait", action="store_true", help="wait for a port or device that is not there yet"
    )


def run(args: argparse.Namespace) -> int:
    import signal
    import threading
    from collections import Counter
    from types import FrameType

    from livedrummer.errors import ConfigError, MidiInputError
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.midi.describe import describe
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.clock import MonotonicClock

    from ..input.base import MidiSource, RawMidi

    if args.seconds is not None and not args.seconds > 0:
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    note_map = load_note_map(args.map)
    clock = MonotonicClock()
    decoder = MessageDecoder(note_map)
    source: MidiSource = kit_source(args, clock, decoder)
    start = clock.now()
    counts: Counter[str] = Counter()

    def show(time_s: float, msg: RawMidi) -> None:
        info = describe(time_s, msg, note_map)
        counts["messages"] += 1
        counts["unknown"] += not info.known
        if args.json:
            print(json.dumps({**info.to_json(), "time_s": round(time_s - start, 6)}), flush=True)
        else:
            print(info.line(start), flush=True)

    source.tap = show
    stop = threading.Event()

    def on_signal(signum: int, _frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    end = float("inf") if args.seconds is None else start + args.seconds
    waiting_since: float | None = None
    next_status = 0.0
    if not args.json:
        print(
            f"monitoring {source.name} with map {note_map.name} (Ctrl-C to stop)",
            file=sys.stderr,
            flush=True,
        )
    try:
        while not stop.is_set() and clock.now() < end:
            if not source.is_open:
                try:
                    source.open()
                except MidiInputError as exc:
                    now = clock.now()
                    waiting_since = now if waiting_since is None else waiting_since
                    if now >= next_status:
                        print(
                            f"monitor: waiting ({now - waiting_since:.0f} s): {exc}",
                            file=sys.stderr,
                            flush=True,
                        )
                        next_status = now + 5.0
                    stop.wait(0.1)
                    continue
                waiting_since = None
                port = getattr(source, "port_name", "") or source.name
                print(f"monitor: listening on {port}", file=sys.stderr, flush=True)
            try:
                source.read(min(0.1, max(0.0, end - clock.now())))
            except MidiInputError as exc:
                print(f"monitor: {exc}; waiting for it", file=sys.stderr, flush=True)
                source.close()
    finally:
        source.close()
    print(f"monitor: {counts['messages']} messages, {counts['unknown']} unknown", file=sys.stderr)
    return 0
