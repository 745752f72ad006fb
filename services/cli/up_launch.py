"""What ``up`` and ``up --stage`` share: the children's argv pieces, the checks before
anything starts, and the supervised run (:func:`supervise`).

Its own module so that ``up`` (one performer) and ``up_stage`` (several) both use it
without importing each other.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from types import FrameType
from typing import TYPE_CHECKING

from .devices import has_screen, kit_source
from .files import DEMO_MAP
from .input import AUDIO_MAP

if TYPE_CHECKING:
    from livedrummer.live.settings import ShowSettings

    from ..process.supervisor import Supervisor


RECORD_GRACE_S = 60.0  # how long past --seconds a set-length recording may take to finish


KEYS_MAP = "general-midi"  # the notes the window's drum keys play (display/keysend.py)


def curve_argv(args: argparse.Namespace) -> dict[str, list[str]]:
    """The CURVE options of each service (see the module docstring), by service name.

    Checks the key files here, so a bad one is one error before anything starts.
    """
    from livedrummer.errors import KeyFileError
    from livedrummer.protocol.keys import PUBLIC_SUFFIX, read_key_file

    from ..wire.net import Security

    Security.from_files(secret=args.curve_secret, allow=args.allow, insecure=args.insecure)
    insecure = ["--insecure"] if args.insecure else []
    if args.curve_secret is None:
        return {"input": insecure, "synth": insecure, "display": []}
    secret = str(args.curve_secret.resolve())
    if args.allow is not None:
        own = read_key_file(args.curve_secret, secret=True).public
        keys = {read_key_file(k, secret=False).public for k in args.allow.glob(f"*{PUBLIC_SUFFIX}")}
        if own not in keys:
            raise KeyFileError(
                f"{args.allow}: --allow folder lacks this rig's public key "
                f"({args.curve_secret.name.removesuffix('_secret')}); its own services "
                "could not connect"
            )
    allow = ["--allow", str(args.allow.resolve())] if args.allow is not None else []
    serve = ["--curve-secret", secret, *allow, *insecure]
    return {
        "input": serve,
        "synth": [*serve, "--server-key", secret],
        "display": ["--curve-secret", secret, "--server-key", secret],
    }


def frame_size(args: argparse.Namespace) -> str:
    """--size, or the default for where the frames go: a 720p window, a small headless frame."""
    return args.size or ("1280x720" if windowed(args) else "640x360")


def windowed(args: argparse.Namespace) -> bool:
    return has_screen() and not args.headless and args.video is None


def recorded(args: argparse.Namespace) -> bool:
    """A recording of a set length: the display itself stops ``--seconds`` after its first
    frame with the drummer, so the video holds the whole show and no more."""
    return args.video is not None and args.seconds is not None


def resolve(args: argparse.Namespace) -> ShowSettings:
    """The show's settings, resolved once here for every process (:mod:`.settings`): the
    map the source's notes mean (``--keys`` plays General MIDI notes, ``--audio`` writes them;
    a kit's is ``--map``, default roland-td), the kit, avatar, D and L, and the sound. An L
    beyond D is one line here; :func:`check_before_start` loads the map."""
    from livedrummer.errors import ConfigError
    from livedrummer.live.settings import AvatarChoice, Delay, ShowSettings, Sound, spec_path

    if args.audio:
        if args.map not in (None, AUDIO_MAP):
            raise ConfigError(f"--map {args.map}: --audio writes {AUDIO_MAP} notes; drop --map")
        note_map = AUDIO_MAP
    elif args.keys:  # the window plays GM drum notes into its port (display/keysend.py)
        note_map = args.map or KEYS_MAP
    else:
        note_map = args.map or DEMO_MAP
    delay = Delay.from_ms(args.lookahead_ms, args.delay_ms, ("--lookahead-ms", "--delay-ms"))
    bone_map = None if args.bone_map is None else str(args.bone_map)
    kit_file = None if args.soundfont is None else str(args.soundfont)
    return ShowSettings(
        note_map=spec_path(note_map) or note_map,
        kit=spec_path(args.kit) or args.kit,
        avatar=AvatarChoice(spec_path(args.avatar), spec_path(bone_map), args.fit),
        delay=delay,
        sound=Sound(args.sound, spec_path(kit_file), args.audio_device),
    )


def check_before_start(args: argparse.Namespace, settings: ShowSettings) -> None:
    """Every option and the source checked here, in the options' units, before any process
    (D and L were checked as ``settings`` were resolved; the map is loaded here, once)."""
    from livedrummer.errors import ConfigError
    from livedrummer.midi.notemap import load_note_map

    from .render import parse_size

    if not 0 < args.fps <= 1000:
        raise ConfigError(f"--fps: expected 0 < fps <= 1000 (got {args.fps:g})")
    parse_size(frame_size(args))
    from livedrummer.render.camera import CAMERA_NAMES

    if args.camera not in CAMERA_NAMES:
        raise ConfigError(f"--camera {args.camera!r}: expected one of {', '.join(CAMERA_NAMES)}")
    if not 0 < args.port_base <= 65535 - 11:
        raise ConfigError(f"--port-base: expected 1..65524 (got {args.port_base})")
    note_map = load_note_map(settings.note_map)  # a bad map is one line, not a failing child
    if args.demo or args.wait or args.keys:
        return
    if args.audio:
        from livedrummer.acoustic.pieces import parse_channel_map
        from livedrummer.acoustic.profile import load_profile
        from livedrummer.timeline.clock import MonotonicClock

        from ..input.audioport import AudioSource

        mapping = parse_channel_map(args.channels) if args.channels else None
        profile = load_profile(args.audio_profile)
        AudioSource(args.audio, MonotonicClock(), profile, mapping).check()
        return
    from livedrummer.midi.decode import MessageDecoder
    from livedrummer.timeline.clock import MonotonicClock

    kit_source(args, MonotonicClock(), MessageDecoder(note_map))


def supervise(args: argparse.Namespace, sup: Supervisor) -> int:
    stopping: list[int] = []

    def on_signal(signum: int, _frame: FrameType | None) -> None:
        stopping.append(signum)
        sup.request_stop()

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGTERM, signal.SIGINT)}
    try:
        sup.start()
        print(f"up: input, synth and display running; {shown_where(args)}", flush=True)
        # A set-length recording ends when the display has recorded it (a minute's grace
        # for a display that never gets a pose); otherwise --seconds ends the rig itself.
        # (the display draws a set-length recording after the show: up to a few times its length)
        grace = RECORD_GRACE_S + 4.0 * args.seconds if recorded(args) else 0.0
        deadline = None if args.seconds is None else time.monotonic() + args.seconds + grace
        while not stopping:
            left = 0.5 if deadline is None else min(0.5, deadline - time.monotonic())
            if left <= 0:
                break
            sup.run_once(left)
            if (windowed(args) or recorded(args)) and sup.quit_by_user("display"):
                break  # the window was closed, or the recording is complete: the show is over
    finally:
        sup.stop()
        for s, handler in old.items():
            signal.signal(s, handler)
    restarts = sum(sup.restarts.values())
    where = "" if windowed(args) else f"; {shown_where(args)}"
    print(f"up: stopped ({restarts} restarts){where}", file=sys.stderr)
    return 0


def shown_where(args: argparse.Namespace) -> str:
    """Where the show goes, as the display writes it: a window, PNG frames (``--png``, not
    with ``--video``) beside ``frames.jsonl``, or only the frame log (and the video)."""
    if windowed(args):
        return "in a window"
    if args.png and args.video is None:
        return f"frames in {args.frames_dir}/ (PNG, and frames.jsonl)"
    video = f"; video {args.video}" if args.video is not None else ""
    return f"frame log in {args.frames_dir / 'frames.jsonl'}{video}"
