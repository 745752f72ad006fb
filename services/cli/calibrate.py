"""``livedrummer calibrate``: measure the kit's input offset by hitting along to a click.

Counts in, then plays ``--clicks`` clicks at ``--bpm`` (sounddevice/PortAudio: the click is
placed by the output stream's DAC time mapped onto the shared clock, so the time of a click
is when it leaves the speaker), and the drummer hits any pad once on each click. Hits come
from the same sources and driver stamps as ``livedrummer input`` (``--midi``, ``--virtual``,
``--serial``). :mod:`livedrummer.live.calibrate` matches hits to clicks and takes their
median lag; the result is written to ``calibration.toml`` as ``input_ms`` (minus the lag:
it is added to every onset), keeping the audio and display offsets as they were, and printed
with its spread. ``--no-sound`` shows the clicks as lines in the terminal instead (and is
what a test uses); ``--dry-run`` prints without writing; ``--json`` prints one object, and
the click schedule (shared-clock seconds) as a first JSON line so a scripted player can
follow it.

Limits: the display offset (a projector's delay) needs a camera or a photodiode and is
not measured here; set ``display_ms`` by hand.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

from .devices import add_api_option, kit_source
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(
        sub, "calibrate", run, "measure the kit's input offset by hitting along to a click"
    )
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="MIDI input port (name or substring)")
    src.add_argument("--virtual", metavar="NAME", help="open a virtual MIDI input port NAME")
    src.add_argument("--serial", metavar="DEV", help="serial device sending raw MIDI bytes")
    p.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(p)
    p.add_argument("--clicks", type=int, default=16, help="clicks to hit along to (default 16)")
    p.add_argument("--bpm", type=float, default=100.0, help="click tempo (default 100)")
    p.add_argument(
        "--no-sound",
        action="store_true",
        help="show the clicks in the terminal instead of playing them",
    )
    p.add_argument("--dry-run", action="store_true", help="print the result, write nothing")
    p.add_argument("--json", action="store_true", help="print JSON (schedule, then result)")


class ClickTrack:
    """Clicks played by a PortAudio output stream at given shared-clock times."""

    RATE = 48_000
    LENGTH_S = 0.015

    def __init__(self, clicks_s: Any) -> None:
        import numpy as np
        import sounddevice as sd

        self._np = np
        self.clicks = np.asarray(clicks_s, np.float64)
        self.stream = sd.OutputStream(
            samplerate=self.RATE, channels=1, dtype="float32", callback=self._fill
        )
        self._offset = 0.0
        self._offset = time.monotonic() - float(self.stream.time)
        self.stream.start()

    def _fill(self, out: Any, frames: int, when: Any, _status: Any) -> None:
        np = self._np
        start = float(when.outputBufferDacTime) + self._offset
        t = start + np.arange(frames) / self.RATE
        out[:, 0] = 0.0
        near = self.clicks[(self.clicks > start - self.LENGTH_S) & (self.clicks < t[-1])]
        for c in near:
            dt = t - c
            on = (dt >= 0) & (dt < self.LENGTH_S)
            out[on, 0] = 0.6 * np.sin(2 * np.pi * 1500.0 * dt[on]) * np.exp(-dt[on] * 300.0)

    def close(self) -> None:
        self.stream.stop()
        self.stream.close()


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.errors import ConfigError
    from livedrummer.live.calibrate import click_times, estimate
    from livedrummer.live.calibration import Calibration, default_path
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.clock import MonotonicClock

    from ..input.base import MidiSource, RawMidi

    if not 4 <= args.clicks <= 200:
        raise ConfigError(f"--clicks {args.clicks}: expected 4..200")
    if not 20 <= args.bpm <= 400:
        raise ConfigError(f"--bpm {args.bpm:g}: expected 20..400")
    clock = MonotonicClock()
    decoder = MessageDecoder(load_note_map("general-midi"))  # unused: the tap is read
    source: MidiSource = kit_source(args, clock, decoder)
    hits: list[float] = []

    def heard(time_s: float, msg: RawMidi) -> None:
        if msg.type == "note_on" and msg.velocity > 0:
            hits.append(time_s)

    source.tap = heard
    source.open()
    player: ClickTrack | None = None
    try:
        clicks = click_times(clock.now() + 2.0, args.bpm, args.clicks)
        if not args.no_sound:
            try:
                player = ClickTrack(clicks)
            except Exception as exc:
                print(
                    f"calibrate: no sound ({exc}); the clicks are shown here instead",
                    file=sys.stderr,
                )
        if args.json:
            print(json.dumps({"clicks_s": clicks.tolist()}), flush=True)
        else:
            print(
                f"hit any pad once on each of the {args.clicks} clicks; starting in 2 s", flush=True
            )
        shown = 0
        end = clicks[-1] + 60.0 / args.bpm
        while clock.now() < end:
            source.read(0.002)
            while not args.json and shown < clicks.size and clock.now() >= clicks[shown]:
                shown += 1
                print(f"  click {shown}/{clicks.size}" + ("" if player else "  *"), flush=True)
    finally:
        if player is not None:
            player.close()
        source.close()
    try:
        got = estimate(clicks, np.array(hits))
    except ValueError as exc:
        raise ConfigError(f"calibrate: {exc}") from None
    old = Calibration.load()
    new = Calibration(
        input_ms=round(-got.median_ms, 2), audio_ms=old.audio_ms, display_ms=old.display_ms
    )
    path = None if args.dry_run else new.save()
    if args.json:
        print(
            json.dumps(
                {
                    "lag_ms": round(got.median_ms, 3),
                    "spread_ms": round(got.spread_ms, 3),
                    "hits_used": got.used,
                    "hits_dropped": got.dropped,
                    "input_ms": new.input_ms,
                    "written": str(path) if path else None,
                }
            )
        )
    else:
        where = f"wrote {path}" if path else f"not written (--dry-run; {default_path()})"
        print(
            f"your hits land {got.median_ms:+.1f} ms after the click (spread ±"
            f"{got.spread_ms:.1f} ms, {got.used} hits, {got.dropped} off the clicks): "
            f"input_ms = {new.input_ms:+.1f}; {where}"
        )
    return 0
