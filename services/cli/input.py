"""``livedrummer input``: run the input daemon on one source until Ctrl-C / SIGTERM.

Once its sockets are bound it prints one JSON line on stdout (``{"service": "input",
"pub": ..., "control": ..., "journal": ...}``) with the real endpoints (useful with
``tcp://127.0.0.1:*``), then serves; a launcher may instead send HELLO to the control
endpoint and wait for READY.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .devices import add_api_option
from .files import DEMO_MAP, add_channel_option
from .keys import add_curve_options, security_from_args
from .parsing import Subparsers, add_command
from .settings import add_settings_option, settings_of

AUDIO_MAP = "general-midi"  # the notes an --audio source writes


def register(sub: Subparsers) -> None:
    from ..input.daemon import DEFAULT_CONTROL, DEFAULT_PUB

    p = add_command(sub, "input", run, "capture a kit, trigger board, file or remote stream")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--midi", metavar="PORT", help="MIDI input port (name or substring)")
    src.add_argument("--serial", metavar="DEV", help="serial device sending raw MIDI bytes")
    src.add_argument("--file", metavar="F.mid", type=Path, help="play a MIDI file as if live")
    src.add_argument("--remote", metavar="ENDPOINT", help="another site's input daemon (pub)")
    src.add_argument(
        "--virtual", metavar="NAME", help="open a virtual MIDI input NAME for a keyboard or DAW"
    )
    src.add_argument(
        "--audio", metavar="DEVICE", help="drums heard through an audio input (name or index)"
    )
    from .transcribe import add_audio_options

    add_audio_options(p)
    p.add_argument(
        "--wait",
        action="store_true",
        help="wait for a --midi port or --serial device that is not there yet "
        "(default: one line naming what exists, exit 2)",
    )
    p.add_argument(
        "--remote-control",
        metavar="ENDPOINT",
        help="--remote: the other site's control endpoint; keeps the remote "
        "drummer's timing (clock offset and jitter buffer) instead of stamping "
        "hits on arrival (default: stamped on arrival)",
    )
    p.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(p)
    p.add_argument("--loop", action="store_true", help="--file: start again at the end")
    p.add_argument(
        "--thru",
        metavar="PORT",
        help="forward what the kit sends to this MIDI port (a DAW or sampler; a "
        "virtual port of that name where none is there) (default: none)",
    )
    p.add_argument(
        "--thru-map",
        choices=("general-midi",),
        help="--thru: re-map notes to General MIDI drums on channel 10 "
        "(default: forwarded unchanged)",
    )
    p.add_argument("--pub", default=DEFAULT_PUB, help=f"publish endpoint (default {DEFAULT_PUB})")
    p.add_argument(
        "--control",
        default=DEFAULT_CONTROL,
        help=f"HELLO/READY endpoint (default {DEFAULT_CONTROL})",
    )
    p.add_argument(
        "--map",
        default="auto",
        help="note map name or .toml path; auto: for --file the bundled map that "
        "knows most of its notes, roland-td for a kit (default auto)",
    )
    add_channel_option(p, "all")  # live: the kit's channel; a keyboard on the port is not drums
    p.add_argument("--performer", type=int, default=0, help="performer id 0..65535 (default 0)")
    p.add_argument(
        "--wait-subscribers",
        type=int,
        default=0,
        metavar="N",
        help="open the source after N subscriptions (1 per SUB topic)",
    )
    p.add_argument("--exit-at-end", action="store_true", help="--file: exit when played")
    p.add_argument("--no-journal", action="store_true", help="do not journal the session")
    p.add_argument(
        "--trace",
        type=Path,
        metavar="FILE",
        help="--audio: on exit, write each hit's times through the daemon (audio "
        "callback, hand-off, detector) to FILE as JSON, for bench transcribe --live "
        "(default: none)",
    )
    p.add_argument(
        "--realtime",
        type=int,
        default=0,
        metavar="PRIO",
        help="SCHED_FIFO priority 1..60 when permitted (default 0: off)",
    )
    p.add_argument(
        "--sessions-dir", type=Path, help="journal folder (default $LIVEDRUMMER_HOME/sessions)"
    )
    p.add_argument(
        "--fsync-interval",
        type=float,
        default=1.0,
        metavar="S",
        help="fsync the journal at most every S s (0: every batch)",
    )
    add_curve_options(p, server=True, client=True)
    add_settings_option(p)


def run(args: argparse.Namespace) -> int:
    import zmq

    from livedrummer.errors import ConfigError
    from livedrummer.midi.channels import parse_channel
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.clock import MonotonicClock

    from ..input.base import Source
    from ..input.daemon import DaemonConfig, InputDaemon
    from ..process.service import serve

    if not 0 <= args.performer <= 0xFFFF:
        raise ConfigError(f"--performer: expected 0..65535 (got {args.performer})")
    security = security_from_args(args)
    if args.realtime:
        from ..process.realtime import request_realtime

        try:  # before any thread starts, so they inherit it
            request_realtime(args.realtime, "input")
        except ValueError as exc:
            raise ConfigError(f"--realtime: {exc}") from None
    clock = MonotonicClock()
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    settings = None
    if args.settings is not None:  # up resolved the map: taken as it is
        settings = settings_of(args, note_map="")
        if args.audio is not None and settings.note_map != AUDIO_MAP:
            raise ConfigError(
                f"--settings {args.settings}: note_map {settings.note_map!r}: "
                f"--audio writes {AUDIO_MAP} notes"
            )
        note_map = load_note_map(settings.note_map)
    elif args.audio is not None:
        note_map = load_note_map(AUDIO_MAP)  # what its onsets' notes mean
    elif args.map != "auto":
        note_map = load_note_map(args.map)
    elif args.file is not None:  # the file's own best map, said in one line as render says it
        from .files import read_performance

        note_map = read_performance(args, args.file, quiet=True)[1]
    else:
        note_map = load_note_map(DEMO_MAP)  # e-kits: the Roland layout most modules follow
    try:
        channel = parse_channel(args.channel)
    except ValueError as exc:
        raise ConfigError(f"--channel: {exc}") from None
    channels = None if channel in ("all", "auto") else frozenset({int(channel)})
    source: Source
    thru = None
    if args.thru is not None and (args.midi is None and args.virtual is None):
        raise ConfigError("--thru forwards a MIDI port's messages: use it with --midi or --virtual")
    if args.thru_map is not None and args.thru is None:
        raise ConfigError("--thru-map re-maps what --thru forwards: add --thru PORT")
    if args.trace is not None and args.audio is None:
        raise ConfigError("--trace records the audio recogniser's hits: use it with --audio")
    if args.audio is not None:
        from livedrummer.acoustic.pieces import parse_channel_map
        from livedrummer.acoustic.profile import load_profile

        from ..input.audioport import AudioSource
        from .transcribe import mix_model

        mapping = parse_channel_map(args.channels) if args.channels else None
        model = mix_model(args) if mapping is None else None
        source = AudioSource(
            args.audio,
            clock,
            load_profile(args.audio_profile),
            mapping,
            args.performer,
            trace=args.trace,
            model=model,
        )
    elif args.file is not None:
        from ..input.fileplayer import FileSource

        source = FileSource(
            args.file, clock, note_map, args.performer, loop=args.loop, channel=channel
        )
        source.load()
    elif args.remote is not None:
        from ..input.remote import RemoteSource

        source = RemoteSource(
            args.remote, clock, ctx, security=security, control=args.remote_control
        )
    elif args.serial is not None:
        from ..input.serialport import BAUD_RATES, SerialSource

        if args.baud not in BAUD_RATES:
            raise ConfigError(f"--baud: expected one of {BAUD_RATES} (got {args.baud})")
        decoder = MessageDecoder(note_map, args.performer, channels)
        source = SerialSource(args.serial, clock, decoder, args.baud)
    else:
        from ..input.midiport import MidiPortSource

        decoder = MessageDecoder(note_map, args.performer, channels)
        virtual = args.virtual is not None
        if args.thru is not None:
            from livedrummer.midi.thrumap import gm_remap

            from ..input.thru import MidiThru

            thru = MidiThru(args.thru, args.api, gm_remap(note_map) if args.thru_map else None)
        source = MidiPortSource(
            args.virtual if virtual else args.midi,
            clock,
            decoder,
            api=args.api,
            virtual=virtual,
            thru=thru.send if thru is not None else None,
        )
    if not args.wait:
        source.check()  # a device that is not there: one line naming what is, exit 2
    config = DaemonConfig(
        pub=args.pub,
        control=args.control,
        performer=args.performer,
        wait_subscribers=args.wait_subscribers,
        exit_at_end=args.exit_at_end,
        journal=not args.no_journal,
        sessions_dir=args.sessions_dir,
        fsync_interval_s=args.fsync_interval,
        meta={"map": note_map.name},
        security=security,
    )
    daemon = InputDaemon(source, config, clock, ctx)
    try:
        if settings is None:  # what the ready line reports: the map this daemon decodes with
            chosen = args.map if args.map != "auto" and args.audio is None else note_map.name
            settings = settings_of(args, note_map=chosen)
        code = serve(daemon, lambda endpoints: endpoints["pub"], {"settings": settings.summary()})
    finally:
        if thru is not None:
            thru.close()
    summary = daemon.summary()
    timing = summary.get("remote_timing")
    line = (
        f"input: {summary['onsets']} onsets, {summary['controls']} controls, "
        f"{summary['gaps']} gaps published"
    )
    if timing is not None:
        line += (
            f"; remote clock {timing['offset_ms']:+.3f} ms (+/- {timing['uncertainty_ms']:.3f}),"
            f" drift {timing['drift_ppm']:+.1f} ppm, played {timing['delay_ms']:.1f} ms behind"
            f" the remote drummer, {timing['late']:.0f} hits late"
        )
    print(line, file=sys.stderr)
    if thru is not None:
        print(
            f"thru: {thru.sent} messages forwarded to {thru.port_name!r}, {thru.failed} failed",
            file=sys.stderr,
        )
    return code
