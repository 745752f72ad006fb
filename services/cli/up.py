"""``livedrummer up``: the live pipeline in one command: input → synth → display, supervised.

Each stage is its own process (:mod:`services.process.supervisor`): started in order, each only
after the previous one said it is ready (no sleeps), restarted with back-off when it dies, all
stopped on Ctrl-C / SIGTERM or after ``--seconds``. ``--demo`` plays the bundled groove
into the pipeline as if from a kit (looping). With a screen (``DISPLAY`` or
``WAYLAND_DISPLAY``) the display opens a window (``--fullscreen --monitor N`` for a
projector; camera keys 1..8, Q quits the window and the rig). With no screen, or with
``--headless``, it renders off screen into ``--frames-dir`` (default ``out/live``): the frame
log ``frames.jsonl``, and numbered PNG frames with ``--png``; ``--video FILE`` records those
frames on show time into an MP4 and, when the rig stops, adds the drum track: the journaled
onsets (the session's journal, a temporary one for ``--demo``) mixed with the built-in kit (or
``--soundfont FILE.sf2``'s) at onset + D (:mod:`services.display.record`), so picture and
sound line up as the audience would see them.

Settings resolved once. Before anything starts, ``up`` resolves what its processes must agree
on (:func:`resolve`): the note map the source's notes mean (``--keys`` plays and ``--audio``
writes General MIDI notes; a kit's map is ``--map``, default roland-td), the kit, the avatar
and its fitting, the delay D and lookahead L (``0 <= L <= D``, checked there), and the sound.
They go into one JSON file in the rig's temporary folder
(:class:`~livedrummer.live.settings.ShowSettings`), and every child is started with
``--settings FILE`` instead of the separate flags; the recording's drum track is mixed from the
same object. Each child reports them in its ready line (``docs/config.md``).

Security. ``--curve-secret RIG.key_secret`` makes every stream of the rig CURVE: the input
daemon and the synth bind as CURVE servers with that key pair, and the synth and the display
connect to them as clients with the same pair (the server key is read from the same file), so
one key made with ``livedrummer keys new`` is all a rig needs. ``--allow DIR`` lets in only
clients whose public key is in DIR, which must then hold the rig's own public key (checked at
start, named in the error) or its own services would be refused. ``--bind ADDR`` serves on
another address than 127.0.0.1 (a remote display); a non-loopback address needs
``--curve-secret`` or ``--insecure``, as for each service.

Limits: endpoints are fixed TCP ports from ``--port-base``; a recording's drum track ignores
the input calibration offset.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

from ..display.keysend import KEYS_PORT
from ..process.program import program_argv
from .devices import add_api_option
from .files import demo_groove
from .keys import add_curve_options
from .parsing import Subparsers, add_command, add_renamed
from .performer import add_avatar_option, add_kit_option, add_style_options, avatar_of, style_argv
from .picture import add_background_option, add_look_option, background_of, lights_argv
from .settings import write_settings
from .show_control import add_osc_options, cues_of, osc_allow

if TYPE_CHECKING:
    from livedrummer.live.settings import ShowSettings

from .up_launch import (
    check_before_start,
    curve_argv,
    frame_size,
    recorded,
    resolve,
    supervise,
    windowed,
)

SYNTH_TOPICS = 1  # the synth subscribes once, to the protocol magic (net.subscribe_protocol)
OSC_SYNTH, OSC_DISPLAY = 12, 13  # their loopback OSC ports (UDP), from --port-base


def register(sub: Subparsers) -> None:
    p = add_command(sub, "up", run, "run the live pipeline: input, synth and display")
    src = p.add_mutually_exclusive_group()  # or the [source] of the rig profile
    src.add_argument(
        "--midi", metavar="PORT", help="MIDI port of the kit (default: the rig profile's source)"
    )
    src.add_argument(
        "--serial", metavar="DEV", help="serial trigger board (default: the rig profile's source)"
    )
    src.add_argument("--demo", action="store_true", help="play the bundled groove as if live")
    src.add_argument(
        "--keys",
        action="store_true",
        help="no kit: the window's drum keys (Z X C V T Y N J K U P E, Shift loud, "
        "Ctrl soft) play into a virtual MIDI input, livedrummer-keys, that a "
        "DAW can also play into",
    )
    src.add_argument(
        "--audio",
        metavar="DEVICE",
        help="audio input of an acoustic kit's microphones (default: the rig profile's source)",
    )
    from .transcribe import add_audio_options

    add_audio_options(p)
    src.add_argument(
        "--stage",
        type=Path,
        metavar="FILE",
        help="a live stage: every performer of FILE with a source (default: one kit)",
    )
    add_kit_option(p)
    add_avatar_option(p)
    add_background_option(p, transparent=False)
    add_look_option(p)
    p.add_argument("--map", help="note map (default roland-td)")
    p.add_argument("--baud", type=int, default=31_250, help="serial baud rate (default 31250)")
    add_api_option(p)
    p.add_argument(
        "--lookahead-ms",
        type=float,
        default=30.0,
        metavar="L",
        help="limb decisions wait L ms for later notes",
    )
    p.add_argument(
        "--delay-ms",
        type=float,
        default=30.0,
        metavar="D",
        help="show the drummer D ms behind the sound, D >= L",
    )
    p.add_argument(
        "--seconds",
        type=float,
        metavar="S",
        help="stop everything after S seconds (default: when stopped)",
    )
    p.add_argument("--headless", action="store_true", help="render off screen even with a screen")
    add_renamed(
        p,
        "--out",
        p.add_argument(
            "--frames-dir",
            type=Path,
            default=Path("out/live"),
            metavar="DIR",
            help="headless frames folder",
        ),
    )
    p.add_argument("--fps", type=float, default=30.0, help="display frames per second")
    p.add_argument(
        "--port-base",
        type=int,
        default=5710,
        help="TCP ports PORT..PORT+11 on --bind, and UDP PORT+12 and +13 on "
        "loopback with --osc or --control (default 5710)",
    )
    p.add_argument(
        "--bind",
        default="127.0.0.1",
        metavar="ADDR",
        help="address the input and synth serve on (default 127.0.0.1)",
    )
    p.add_argument(
        "--png",
        action="store_true",
        help="headless: also write every frame as a PNG into --frames-dir (about 9 GB "
        "an hour at 640x360; default: frames.jsonl only)",
    )
    p.add_argument("--no-png", action="store_true", help=argparse.SUPPRESS)  # the old default
    p.add_argument("--no-journal", action="store_true", help="do not journal the session")
    p.add_argument(
        "--video",
        type=Path,
        metavar="FILE",
        help="headless: record the show and its drum track as MP4 (default: none)",
    )
    p.add_argument(
        "--soundfont",
        type=Path,
        metavar="SF2",
        help="--video and --sound: drum sounds from this General MIDI SoundFont "
        "(default: the built-in kit)",
    )
    p.add_argument(
        "--sfz",
        type=Path,
        metavar="SFZ",
        dest="soundfont",
        help="drum sounds from this SFZ sampled kit (instead of --soundfont; "
        "default: the built-in kit)",
    )
    p.add_argument(
        "--sound",
        action="store_true",
        help="the display sounds each onset at onset + D (the built-in kit, --soundfont or --sfz)",
    )
    p.add_argument(
        "--audio-device",
        metavar="NAME",
        help="--sound: the output, a device name or part of it "
        "(default: the system's default output)",
    )
    p.add_argument(
        "--size", help="frame size WIDTHxHEIGHT (default 1280x720 in a window, 640x360 headless)"
    )
    p.add_argument("--fullscreen", action="store_true", help="window: full screen (projectors)")
    p.add_argument("--camera", default="stage", help="display camera (default stage)")
    p.add_argument(
        "--overlay",
        default="",
        metavar="LIST",
        help="SMED's strips over the drummer: score, joints or both; keys O and G in "
        "the window (default: none)",
    )
    p.add_argument(
        "--rig",
        type=Path,
        metavar="FILE",
        help="rig profile whose values are the defaults of these options "
        "(default $LIVEDRUMMER_HOME/rig.toml when it exists)",
    )
    p.add_argument(
        "--wait",
        action="store_true",
        help="wait for a --midi port or --serial device that is not there yet "
        "(default: one line naming what exists, exit 2)",
    )
    p.add_argument("--monitor", type=int, default=0, help="window: monitor for --fullscreen")
    add_style_options(p)
    add_osc_options(
        p,
        "every /livedrummer address, forwarded to the synth and the display "
        "on UDP ports PORT_BASE+12 and +13",
    )
    p.add_argument(
        "--control",
        type=Path,
        metavar="FILE",
        help="MIDI controller map (livedrummer control learn) applied from "
        "--control-midi (default: none)",
    )
    p.add_argument(
        "--control-midi",
        metavar="PORT",
        help="the MIDI controller's port, for --control (default: none)",
    )
    add_curve_options(p, server=True, client=False)
    # what "left at its default" means for the rig profile (see apply_profile)
    p.set_defaults(up_defaults={a.dest: a.default for a in p._actions})


def specs(args: argparse.Namespace, settings: Path, sessions: Path | None = None) -> list:  # type: ignore[type-arg]
    """The rig's services in start order; each is given the resolved ``settings`` file."""
    from ..process.supervisor import ServiceSpec

    base = args.port_base
    ep = {
        name: f"tcp://{args.bind}:{base + k}"
        for name, k in (("in_pub", 0), ("in_ctl", 1), ("syn_pub", 10), ("syn_ctl", 11))
    }
    # Clients reach the servers through loopback unless they serve on one given address.
    near = {name: e.replace("tcp://0.0.0.0:", "tcp://127.0.0.1:") for name, e in ep.items()}
    curve = curve_argv(args)
    given = ["--settings", str(settings)]  # map, kit, avatar, D, L and sound: resolve(args)
    me = program_argv()
    source: list[str]
    if args.demo:
        source = ["--file", str(demo_groove()), "--loop"]
    elif args.keys:  # the window plays GM drum notes into this port (display/keysend.py)
        source = ["--virtual", KEYS_PORT, "--api", args.api]
    elif args.serial:
        source = ["--serial", args.serial, "--baud", str(args.baud)]
    elif args.audio:
        source = ["--audio", args.audio]
        source += ["--channels", args.channels] if args.channels else []
        source += ["--audio-profile", args.audio_profile] if args.audio_profile else []
        source += ["--recogniser", args.recogniser]
    else:
        source = ["--midi", args.midi, "--api", args.api]
    if sessions is not None:
        journal = ["--sessions-dir", str(sessions)]
    else:
        journal = ["--no-journal"] if args.no_journal or args.demo else []
    # The input service waits for its device: one that vanishes mid-show (and the service
    # restarted meanwhile) must be waited for, not refused; up checked it once at start.
    source += [] if args.demo or args.keys else ["--wait"]
    input_argv = [*me, "input", *source, *given, "--pub", ep["in_pub"],
                  "--control", ep["in_ctl"], "--wait-subscribers", str(SYNTH_TOPICS),
                  *journal, *curve["input"]]  # fmt: skip
    synth_argv = [*me, "synth", "--sub", near["in_pub"], "--pub", ep["syn_pub"],
                  "--control", ep["syn_ctl"], *given, *style_argv(args),
                  *curve["synth"]]  # fmt: skip
    display_argv = [*me, "display", "--live", "--sub", near["syn_pub"], *given,
                    "--camera", args.camera, "--fps", str(args.fps), "--size", frame_size(args),
                    "--synth-control", near["syn_ctl"], *curve["display"]]  # fmt: skip
    if args.osc is not None or args.control is not None:  # up's OSC port forwards here
        synth_argv += ["--osc", str(base + OSC_SYNTH)]
        display_argv += ["--osc", str(base + OSC_DISPLAY)]
    if args.cues is not None:  # bar cues fire in the synth, by name over OSC in both
        cues = ["--cues", str(args.cues.resolve())]
        synth_argv += cues
        display_argv += cues
    display_argv += ["--background", args.background] if args.background else []
    display_argv += lights_argv(args)  # the lights over the kit's [lights]
    display_argv += ["--overlay", args.overlay] if args.overlay else []
    display_argv += ["--keys-port", KEYS_PORT] if args.keys else []
    if windowed(args):
        display_argv += ["--aa", "0", "--monitor", str(args.monitor)]
        display_argv += ["--fullscreen"] if args.fullscreen else []
    else:
        display_argv += ["--headless", "--frames-dir", str(args.frames_dir)]
        display_argv += [] if args.png and args.video is None else ["--no-png"]
        display_argv += ["--video", str(args.video)] if args.video is not None else []
        display_argv += ["--seconds", str(args.seconds)] if recorded(args) else []
    return [
        ServiceSpec("input", input_argv),
        ServiceSpec("synth", synth_argv),
        ServiceSpec("display", display_argv, ends_rig=windowed(args) or recorded(args)),
    ]


def apply_profile(args: argparse.Namespace, defaults: dict[str, object]) -> Path | None:
    """Values of the rig profile for every option the command line left at its default; the
    profile's path (None when there is none). Raises ConfigError without any source."""
    from livedrummer.errors import ConfigError
    from livedrummer.live.profile import RigProfile, default_path

    path = args.rig if args.rig is not None else default_path()
    used: Path | None = None
    if args.rig is not None or path.exists():
        profile = RigProfile.load(path)
        source_given = bool(args.midi or args.serial or args.demo or args.audio or args.keys)
        for key, value in profile.options.items():
            if key in ("midi", "serial", "demo") and source_given:
                continue
            if getattr(args, key) == defaults.get(key):
                setattr(args, key, value)
        used = path
    if not (args.midi or args.serial or args.demo or args.audio or args.keys):
        where = f" (none in {used})" if used is not None else ""
        raise ConfigError(
            f"up: give --midi PORT, --serial DEV or --demo (or --audio DEVICE), or "
            f"a [source] in rig.toml{where}"
        )
    return used


def run(args: argparse.Namespace) -> int:
    from livedrummer.errors import ConfigError

    from ..process.supervisor import Supervisor

    if args.stage is not None:  # several performers: services.cli.up_stage
        from .up_stage import run_stage

        return run_stage(args)
    apply_profile(args, args.up_defaults)
    from livedrummer.render.overlay import parse_overlays

    parse_overlays(args.overlay)  # a typo is one line before anything starts

    if args.seconds is not None and not args.seconds > 0:
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    if args.video is not None and args.no_journal:
        raise ConfigError("--video: the drum track comes from the journal; drop --no-journal")
    if args.soundfont is not None:  # now, not after the show
        from livedrummer.audio.kitfile import check_kit_file

        check_kit_file(args.soundfont)
    avatar_of(args)  # a bad --avatar is one line here, before three services start
    background_of(args, window=True)  # and a bad --background
    if args.preset is not None:  # and a bad --preset
        from livedrummer.body.expression import load_expression

        load_expression(args.preset)
    settings = resolve(args)
    check_before_start(args, settings)
    allow = osc_allow(args)
    cues_of(args)  # a bad cue list is one line before anything starts
    mapping = None
    if (args.control is None) != (args.control_midi is None):
        raise ConfigError("--control FILE and --control-midi PORT go together")
    if args.control is not None:
        from livedrummer.live.controlmap import load_control_map

        mapping = load_control_map(args.control)
    with tempfile.TemporaryDirectory(prefix="livedrummer-up-") as tmp:
        sessions = None
        if args.video is not None:
            from ..input.journal import sessions_dir

            sessions = Path(tmp) if args.demo else sessions_dir()
            args.video.parent.mkdir(parents=True, exist_ok=True)
        started = time.time()
        router = bridge = None
        if args.osc is not None or mapping is not None:
            import logging

            from ..show.osc import DISPLAY_ADDRESSES, SYNTH_ADDRESSES, OscRouter

            routes = {
                "synth": (SYNTH_ADDRESSES, args.port_base + OSC_SYNTH),
                "display": (DISPLAY_ADDRESSES, args.port_base + OSC_DISPLAY),
            }
            # a controller alone gets a loopback port of its own (0: the system picks one)
            port = args.osc if args.osc is not None else 0
            router = OscRouter(port, routes, logging.getLogger("livedrummer.up"), allow)
            print(
                f"up: OSC on udp port {router.port} "
                f"({'loopback and ' + ', '.join(allow) if allow else 'loopback only'})",
                flush=True,
            )
            router.start()
        if mapping is not None and router is not None:
            from ..show.controller import ControllerBridge

            bridge = ControllerBridge(args.control_midi, mapping, router.port, args.api).start()
            print(
                f"up: controller {args.control_midi} steers the show ({args.control})", flush=True
            )
        given = write_settings(settings, Path(tmp))
        try:
            code = supervise(args, Supervisor(specs(args, given, sessions)))
        finally:
            if bridge is not None:
                bridge.stop()
            if router is not None:
                router.stop()
        if code == 0 and args.video is not None and sessions is not None:
            add_drum_track(settings, args.video, sessions, started)
    return code


def add_drum_track(settings: ShowSettings, video: Path, sessions: Path, started: float) -> None:
    """Mix the journaled onsets at onset + D, their chokes applied, into the recording (see the
    module docstring): D, the kit, the map and the kit file are the ``settings`` the rig's
    processes were given, so the drum track is what the display sounded and drew."""
    import numpy as np

    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.protocol.journal import SUFFIX
    from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE

    from ..display.record import Timing, mux_audio, recording_track
    from ..input.journal import load_journal

    timing = Timing.load(video)
    delay_s = settings.delay.delay_s
    kit_file = None if settings.sound.kit_file is None else Path(settings.sound.kit_file)
    journals = [
        load_journal(path)
        for path in sorted(sessions.glob(f"*{SUFFIX}"))
        if path.stat().st_mtime >= started - 1.0
    ]
    onsets = np.concatenate([j.onsets for j in journals] or [np.zeros(0, ONSET_DTYPE)])
    controls = np.concatenate([j.controls for j in journals] or [np.zeros(0, CONTROL_DTYPE)])
    track = recording_track(
        onsets,
        controls,
        timing,
        delay_s=delay_s,
        kit=load_kit(settings.kit),
        note_map=load_note_map(settings.note_map),
        soundfont=kit_file,
    )
    mux_audio(video, track)
    duration = timing.frames / timing.fps
    # the rig keeps playing while the display draws a set-length recording: count the hits
    # the video holds, not every one journaled
    sounded = onsets["time_s"].astype(np.float64) + delay_s - timing.show0_s
    heard = int(np.count_nonzero((sounded >= 0.0) & (sounded < duration)))
    print(
        f"up: wrote {video.resolve()} ({duration:.1f} s, {timing.frames} frames, "
        f"{heard} hits in its drum track)",
        flush=True,
    )
