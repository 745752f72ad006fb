"""``livedrummer synth``: the online stroke synthesizer between an input daemon and displays.

Once its sockets are bound it prints one JSON line on stdout (``{"service": "synth", "pub":
..., "control": ..., "sub": ...}``), tells a launcher or systemd it is ready, and serves
until Ctrl-C / SIGTERM; at exit it prints a one-line summary on stderr.
"""

from __future__ import annotations

import argparse
import logging
import sys
from contextlib import nullcontext
from typing import TYPE_CHECKING

from .keys import add_curve_options, security_from_args
from .parsing import Subparsers, add_command
from .performer import add_avatar_option, add_kit_option, add_style_options, rig_for
from .settings import add_settings_option, played_by, settings_of
from .show_control import add_osc_options, cues_of, osc_allow

if TYPE_CHECKING:
    from livedrummer.live.settings import Delay
    from livedrummer.stage.variation import Variation

log = logging.getLogger("livedrummer.synth")


def register(sub: Subparsers) -> None:
    from ..synth.service import DEFAULT_CONTROL, DEFAULT_PUB, DEFAULT_SUB

    p = add_command(sub, "synth", run, "turn live onsets into drummer poses (online)")
    p.add_argument("--sub", default=DEFAULT_SUB, help=f"input daemon's pub (default {DEFAULT_SUB})")
    p.add_argument("--pub", default=DEFAULT_PUB, help=f"pose endpoint (default {DEFAULT_PUB})")
    p.add_argument(
        "--control",
        default=DEFAULT_CONTROL,
        help=f"HELLO/READY endpoint (default {DEFAULT_CONTROL})",
    )
    add_kit_option(p)
    add_avatar_option(p)
    p.add_argument(
        "--map",
        default="roland-td",
        help="note map, for hi-hat pedal and chokes (default roland-td)",
    )
    p.add_argument(
        "--lookahead-ms",
        type=float,
        default=30.0,
        metavar="L",
        help="limb decisions wait L ms for later notes (default 30)",
    )
    p.add_argument(
        "--delay-ms",
        type=float,
        default=30.0,
        metavar="D",
        help="show the drummer D ms behind the sound, D >= L (default 30)",
    )
    p.add_argument("--rate", type=float, default=240.0, help="pose samples per second")
    p.add_argument("--tick-hz", type=float, default=120.0, help="pose messages per second")
    p.add_argument("--no-predict", action="store_true", help="no upswing before expected hits")
    p.add_argument(
        "--no-provisional",
        action="store_true",
        help="publish a hit only once its hand is decided, L after it",
    )
    p.add_argument(
        "--curves-in-process",
        action="store_true",
        help="re-animate on a thread of this process, not in a worker process "
        "(the answers then share the interpreter with it; for comparison)",
    )
    p.add_argument("--performer", type=int, default=0, help="performer id 0..65535 (default 0)")
    p.add_argument(
        "--vary",
        type=int,
        default=None,
        metavar="SEED",
        help="be an ensemble copy: seeded smooth delay and gain per onset (default: not a copy)",
    )
    p.add_argument(
        "--vary-ms",
        type=float,
        default=30.0,
        metavar="W",
        help="with --vary, most delay in ms, capped at D - L (default 30)",
    )
    p.add_argument(
        "--vary-amplitude",
        type=float,
        default=0.2,
        metavar="R",
        help="with --vary, velocities scaled within 1 +- R (default 0.2)",
    )
    add_style_options(p)
    add_osc_options(p, "preset, param, state")
    add_curve_options(p, server=True, client=True)
    add_settings_option(p)


def run(args: argparse.Namespace) -> int:
    import numpy as np
    import zmq

    from livedrummer.body.expression import load_expression
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.errors import ConfigError
    from livedrummer.live.calibration import Calibration
    from livedrummer.live.synth import LiveSynth, SynthParams
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.clock import MonotonicClock

    from ..process.service import serve
    from ..synth.curveworker import CurveWorker
    from ..synth.service import SynthConfig, SynthService

    settings = settings_of(args, note_map=args.map)  # --settings FILE, or these flags
    try:  # the delay was checked with the settings; the rate is the synth's own
        params = SynthParams(
            lookahead_s=settings.delay.lookahead_s,
            delay_s=settings.delay.delay_s,
            rate_hz=args.rate,
            predict=not args.no_predict,
            provisional=not args.no_provisional,
        )
    except ValueError as exc:
        raise ConfigError(f"--rate: {exc}") from None
    if not 0 < args.tick_hz <= 1000:
        raise ConfigError(f"--tick-hz: expected 0 < hz <= 1000 (got {args.tick_hz})")
    note_map = load_note_map(settings.note_map)
    cc_open = np.array([note_map.openness(v) for v in range(128)])
    kit, avatar = played_by(settings)
    rig = rig_for(kit, avatar)
    expression = load_expression(args.preset) if args.preset else None
    strokes = StrokeParams(model=args.strokes)
    # the window is re-animated in a worker process (services.synth.curveworker), so that a
    # hit's answer never waits for the interpreter while it runs
    worker = None if args.curves_in_process else CurveWorker(rig, params.blend_s, strokes)
    synth = LiveSynth(
        rig,
        params,
        strokes=strokes,
        cc_open=cc_open,
        note_map=note_map,
        expression=expression,
        curves=worker,
    )
    vary = vary_of(args, settings.delay)
    calibration = Calibration.load()
    config = SynthConfig(
        sub=args.sub,
        pub=args.pub,
        control=args.control,
        performer=args.performer,
        tick_hz=args.tick_hz,
        input_offset_s=calibration.input_ms / 1000.0,
        security=security_from_args(args),
        avatar="" if avatar is None else avatar.digest,
        osc_port=args.osc,
        osc_allow=osc_allow(args),
        preset=args.preset or "neutral",
        cues=cues_of(args),
        vary=vary,
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    service = SynthService(synth, config, MonotonicClock(), ctx)
    with worker if worker is not None else nullcontext():
        code = serve(service, lambda endpoints: endpoints["pub"], {"settings": settings.summary()})
    s = service.summary()
    p50, p99 = ("-" if v is None else v for v in s["answer_ms"])
    print(
        f"synth: {s['onsets']} onsets ({s['missing']} lost upstream), "
        f"{s['pose_samples']} pose samples in {s['pose_messages']} messages, "
        f"{s['animations']} re-animations, {s['quick_contacts']} quick contacts, "
        f"answered in {p50}/{p99} ms p50/p99, {s['late_contacts']} contacts late, "
        f"{s['merged_notes']} notes merged into a stroke; "
        f"played with preset {args.preset or 'neutral'}, {args.strokes} strokes",
        file=sys.stderr,
    )
    return code


def vary_of(args: argparse.Namespace, delay: Delay) -> Variation | None:
    """The copy's live variation from ``--vary``, its delay capped at D - L (``bounded``)."""
    from livedrummer.errors import ConfigError
    from livedrummer.stage.variation import Variation, bounded

    if args.vary is None:
        return None
    if not 0 <= args.vary_ms <= 250:
        raise ConfigError(f"--vary-ms {args.vary_ms:g}: expected 0..250 ms")
    if not 0 <= args.vary_amplitude < 1:
        raise ConfigError(f"--vary-amplitude {args.vary_amplitude:g}: expected 0 <= R < 1")
    wanted = Variation(warp_s=args.vary_ms / 1000.0, amplitude=args.vary_amplitude, seed=args.vary)
    vary = bounded(wanted, delay.delay_s, delay.lookahead_s)
    if vary.warp_s < wanted.warp_s:
        log.warning(
            "--vary-ms %g capped at %g ms: D - L (--delay-ms minus --lookahead-ms)",
            args.vary_ms,
            vary.warp_s * 1000,
        )
    return vary
