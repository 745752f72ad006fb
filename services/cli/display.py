"""``livedrummer display FILE.mid``: play a MIDI file in a window (or full screen on a projector).

Keys: space play/pause, left/right step a frame, shift+left/right seek 5 s, home/end, r
reverse, +/- speed, 0 normal speed, m set a marker, [ ] previous/next marker, 1..8 cameras
(stage, front, drummer, overhead, left, right, back, kick), o the scrolling score and g the
joint-angle graph (``--overlay score,joints`` shows them from the start), q or Esc quit. On a
machine with no screen use ``livedrummer render``. The limbs are those of
:func:`livedrummer.sticking.stick_performance` (``--sticking``, ``--score``), as ``livedrummer
sticking`` prints them.

Sound: the file window plays the drum track (the built-in kit, or ``--soundfont FILE.sf2``'s)
on the default output or ``--audio-device NAME`` (PortAudio: JACK or ALSA), and the picture
follows the sound's clock (:mod:`services.display.audio_out`); at speeds other than 1x and in
reverse the sound fades out and is muted (the readout says so). ``--no-sound``, or no output
device, plays silently on the monotonic clock.

Options share their names with the other commands: ``--seconds`` (as in ``up`` and ``demo``)
stops the show (the file window or ``--live``), ``--frames-dir`` (as in ``render`` and ``up``)
is where ``--live --headless`` writes its frames, ``--max-frames`` stops it after so many.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.render.camera import CAMERA_NAMES

from .files import DEMO_MAP, add_channel_option, demo_groove, read_performance
from .keys import add_curve_options, security_from_args
from .parsing import Subparsers, add_command, add_renamed
from .performer import add_avatar_option, add_kit_option, add_motion_options, avatar_of, fitted
from .picture import add_background_option, add_look_option, background_of, check_aa, lights_of
from .render import body_scene, parse_size
from .settings import add_settings_option, played_by, settings_of
from .show_control import add_osc_options, cues_of, osc_allow

if TYPE_CHECKING:
    from ..display.audio_out import TrackPlayer


def register(sub: Subparsers) -> None:
    p = add_command(sub, "display", run)
    p.add_argument(
        "file",
        nargs="?",
        help="Standard MIDI File (default: the demo groove; "
        "--live --practice: the reference the teacher plays)",
    )
    add_kit_option(p)
    p.add_argument(
        "--map",
        help="note map name or .toml path (default auto: the bundled map "
        "that knows the most of the file's notes; roland-td for the demo; --live "
        "--sound: the synth's map, which reads its grabs and pedal, default "
        "roland-td)",
    )
    add_channel_option(p)
    p.add_argument("--camera", default="stage", choices=CAMERA_NAMES, help="first viewpoint")
    p.add_argument("--size", default="1280x720", help="window size WIDTHxHEIGHT")
    p.add_argument("--fullscreen", action="store_true", help="full screen (projectors)")
    p.add_argument(
        "--screenshot",
        type=Path,
        metavar="PNG",
        help="file window: its last frame as PNG at close (default none)",
    )
    p.add_argument("--monitor", type=int, default=0, help="monitor index for --fullscreen")
    p.add_argument(
        "--aa",
        type=int,
        default=4,
        metavar="N",
        help="multisample N: 0, 2, 4 or 8 (default 4; the live window: FXAA where N > 0)",
    )
    add_renamed(
        p,
        "--quit-after",
        p.add_argument(
            "--seconds",
            type=float,
            metavar="S",
            help="stop after S seconds; --live: S seconds after the first frame with the drummer "
            "(default: when closed or stopped)",
        ),
    )
    p.add_argument(
        "--overlay",
        default="",
        metavar="LIST",
        help="strips shown first: score, joints or both; keys o, g (default: none)",
    )
    sound = p.add_argument_group("sound (the file window)")
    sound.add_argument(
        "--audio-device",
        metavar="NAME",
        help="sound output: a device name or part of it, e.g. 'system, JACK' "
        "(default: the system's default output)",
    )
    sound.add_argument(
        "--soundfont",
        type=Path,
        metavar="SF2",
        help="drum sounds from this General MIDI SoundFont via FluidSynth "
        "(default: the built-in kit)",
    )
    sound.add_argument(
        "--sfz",
        type=Path,
        metavar="SFZ",
        dest="soundfont",
        help="drum sounds from this SFZ sampled kit (instead of --soundfont; "
        "default: the built-in kit)",
    )
    sound.add_argument("--no-sound", action="store_true", help="a silent window")
    sound.add_argument(
        "--midi-out",
        metavar="PORT",
        help="file window: send the file's notes to this MIDI port (a sampler; "
        "a virtual port of that name where none is there) as the picture "
        "plays them (default: none)",
    )
    sound.add_argument(
        "--frame-log",
        type=Path,
        metavar="JSONL",
        help="file window: per frame the monotonic time after the swap and "
        "the position shown (default: none)",
    )
    add_motion_options(p)
    add_avatar_option(p)
    add_background_option(p, transparent=False)
    add_look_option(p)
    live = p.add_argument_group("live (poses from a running synth)")
    live.add_argument("--live", action="store_true", help="show a synth's poses as they come")
    live.add_argument(
        "--sub",
        default="tcp://127.0.0.1:5720",
        help="the synth's pose endpoint (default tcp://127.0.0.1:5720)",
    )
    live.add_argument(
        "--keys-port",
        metavar="PORT",
        help="window: the drum keys (Z X C V T Y N J K U P E) play MIDI notes into "
        "this input port, e.g. an `input --virtual PORT` (default: keys play "
        "nothing live)",
    )
    live.add_argument(
        "--control",
        metavar="ENDPOINT",
        help="answer HELLO with READY here, e.g. tcp://127.0.0.1:5731 (default: no control socket)",
    )
    live.add_argument(
        "--synth-control",
        metavar="ENDPOINT",
        help="ask the synth here which avatar it plays; warn when it is not "
        "--avatar (default: not asked)",
    )
    live.add_argument(
        "--stage",
        type=Path,
        metavar="FILE",
        help="draw every live performer of this stage file; --sub lists their "
        "synths' pose endpoints, comma-separated, in the file's order "
        "(default: one drummer)",
    )
    live.add_argument("--headless", action="store_true", help="no window: render off screen")
    live.add_argument(
        "--practice",
        metavar="ENDPOINT",
        help="draw a practice rig's readout from this endpoint, and its teacher "
        "playing FILE (livedrummer practice starts this; default: none)",
    )
    live.add_argument(
        "--teacher",
        default="off",
        metavar="MODE",
        help="--practice: ghost, ahead[:SECONDS] or off (default off)",
    )
    live.add_argument(
        "--sound",
        action="store_true",
        help="sound each onset the synth forwards at its show time (onset + D), "
        "on --audio-device: the built-in kit, --soundfont or --sfz",
    )
    add_renamed(
        live,
        "--frames",
        live.add_argument(
            "--max-frames",
            type=int,
            metavar="N",
            help="stop after N frames (default: when stopped)",
        ),
    )
    add_renamed(
        live,
        "--out",
        live.add_argument(
            "--frames-dir",
            type=Path,
            metavar="DIR",
            help="write frame PNGs and frames.jsonl into DIR (default: none)",
        ),
    )
    live.add_argument("--fps", type=float, default=60.0, help="frames per second (default 60)")
    live.add_argument(
        "--clock",
        choices=("auto", "audio", "monotonic"),
        default="auto",
        help="frame clock: the audio output's (auto: when not headless)",
    )
    live.add_argument(
        "--no-png", action="store_true", help="--frames-dir: frames.jsonl only, no PNGs"
    )
    live.add_argument(
        "--video",
        type=Path,
        metavar="FILE",
        help="with --headless: record the frames on show time as MP4 (default: none)",
    )
    live.add_argument(
        "--no-render",
        action="store_true",
        help="only log frames (benchmarks without a GPU context)",
    )
    live.add_argument(
        "--no-render-ahead",
        action="store_true",
        help="draw each frame for when it is begun, not when it is done",
    )
    add_osc_options(p, "--live: camera, camera/cut, blackout, state")
    add_curve_options(p, server=False, client=True)
    add_settings_option(p)


def run(args: argparse.Namespace) -> int:
    check_aa(args.aa)
    if args.settings is not None and not args.live:
        from livedrummer.errors import ConfigError

        raise ConfigError("--settings: the settings of a live display (display --live)")
    if args.live and args.stage is not None:
        from .stage_display import run_stage_live

        return run_stage_live(args)
    if args.live:
        return run_live(args)
    import dataclasses

    from livedrummer.kit.loader import load_kit
    from livedrummer.render.overlay import parse_overlays

    from ..display.window import WindowOptions, show

    background = background_of(args, window=True)
    if args.soundfont is not None:
        from livedrummer.audio.kitfile import check_kit_file

        check_kit_file(args.soundfont)
    source = Path(args.file) if args.file else demo_groove()
    performance, note_map = read_performance(args, source, "auto" if args.file else DEMO_MAP)
    if not performance.onsets.size:  # said on stderr: nothing for the drummer to play
        return 0
    options = WindowOptions(
        size=parse_size(args.size),
        fullscreen=args.fullscreen,
        monitor=args.monitor,
        camera=args.camera,
        samples=args.aa,
        quit_after_s=args.seconds,
        overlays=parse_overlays(args.overlay),
        screenshot=args.screenshot,
        background=background,
        frame_log=args.frame_log,
    )
    kit, avatar = fitted(args, load_kit(args.kit), avatar_of(args))
    options = dataclasses.replace(options, lights=lights_of(args, kit))
    body = body_scene(args, performance, kit, note_map, avatar)
    sound = None
    if not args.no_sound:
        from livedrummer.audio.synth import SAMPLE_RATE

        from ..display.audio_out import open_player, window_track

        def sound() -> TrackPlayer | None:
            track = window_track(performance, body, args.soundfont)
            return open_player(track, SAMPLE_RATE, args.audio_device)

    midi = None
    if args.midi_out is not None:
        import sys

        from ..display.midi_out import MidiFileOut

        midi = MidiFileOut(performance.onsets, args.midi_out)
    try:
        show(performance, kit, options, body=body, avatar=avatar, sound=sound, midi=midi)
    finally:
        if midi is not None:
            midi.close()
            print(f"display: {midi.sent} notes sent to {midi.out.port_name!r}", file=sys.stderr)
    return 0


def run_live(args: argparse.Namespace) -> int:
    """``--live``: subscribe to poses and render them on the frame clock until stopped."""
    import logging
    import sys

    import zmq

    from livedrummer.errors import ConfigError
    from livedrummer.live.calibration import Calibration
    from livedrummer.render.overlay import parse_overlays

    from ..display.live import (
        AudioFrameClock,
        FrameClock,
        LiveConfig,
        LiveDisplay,
        MonotonicFrameClock,
    )
    from ..process.service import serve

    # --settings FILE (from up): kit, avatar and sound as resolved there; a practice display's
    # --map is its teacher's reference, not the kit's
    settings = settings_of(
        args, note_map=args.map or DEMO_MAP, skip=("map",) if args.practice is not None else ()
    )
    window = None
    overlays = parse_overlays(args.overlay)
    background = background_of(args, window=True)  # live video has no alpha: opaque only
    if not args.headless:
        from ..display.window import WindowOptions

        if args.video is not None or args.frames_dir is not None:
            raise ConfigError(
                "display --live: --video and --frames-dir record off screen: add --headless"
            )
        window = WindowOptions(
            size=parse_size(args.size),
            fullscreen=args.fullscreen,
            monitor=args.monitor,
            camera=args.camera,
            samples=args.aa,
            vsync=False,
            background=background,
            overlays=overlays,
            keys_port=args.keys_port,
        )
    if args.max_frames is not None and args.max_frames < 1:
        raise ConfigError(f"--max-frames: expected >= 1 (got {args.max_frames})")
    if not 0 < args.fps <= 1000:
        raise ConfigError(f"--fps: expected 0 < fps <= 1000 (got {args.fps})")
    calibration = Calibration.load()
    kit, avatar = played_by(settings)
    clock: FrameClock
    if args.clock == "audio":
        clock = AudioFrameClock(calibration.audio_ms / 1000.0)
    elif args.clock == "auto" and window is not None:
        from ..display.context import DisplayError

        try:  # a stage window follows the sound the audience hears, where there is an output
            clock = AudioFrameClock(calibration.audio_ms / 1000.0)
        except DisplayError as exc:
            logging.getLogger("livedrummer.display").warning(
                "%s: frames on the monotonic clock", exc
            )
            clock = MonotonicFrameClock(calibration.audio_ms / 1000.0)
    else:
        clock = MonotonicFrameClock(calibration.audio_ms / 1000.0)
    config = LiveConfig(
        sub=args.sub,
        fps=args.fps,
        frames=args.max_frames,
        out=args.frames_dir,
        size=parse_size(args.size),
        camera=args.camera,
        display_offset_s=calibration.display_ms / 1000.0,
        render=not args.no_render,
        png=not args.no_png,
        security=security_from_args(args),
        window=window,
        video=args.video,
        render_ahead=not args.no_render_ahead,
        seconds=args.seconds,
        control=args.control,
        avatar=avatar,
        osc_port=args.osc,
        osc_allow=osc_allow(args),
        cues=cues_of(args),
        background=background,
        overlays=overlays,
        lights=lights_of(args, kit),
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    if args.practice is not None:
        config.extra = practice_view(args, ctx, kit, avatar)
    if args.synth_control is not None:  # one line when the synth plays another avatar
        from ..display.avatar_check import check_synth_avatar

        check_synth_avatar(ctx, args.synth_control, avatar, security_from_args(args))
    if args.seconds is not None and not args.seconds > 0:  # counted from the first pose drawn
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    display = LiveDisplay(kit, config, clock, ctx)
    sound = None
    if settings.sound.on:
        from ..display.live_sound import LiveSound, SoundConfig

        sfz = sf2 = None
        kit_file = settings.sound.kit_file
        if kit_file is not None:  # an SFZ kit (--sfz) or a SoundFont (--soundfont)
            from livedrummer.audio.kitfile import check_kit_file, is_sfz

            check_kit_file(Path(kit_file))
            if is_sfz(Path(kit_file)):
                sfz = kit_file
            else:
                sf2 = kit_file
        from livedrummer.midi.notemap import load_note_map

        load_note_map(settings.note_map)  # a bad map is one line here, not a silent sound
        sound = LiveSound(
            SoundConfig(
                args.sub,
                settings.sound.device,
                settings.kit,
                security_from_args(args),
                sfz=sfz,
                soundfont=sf2,
                note_map=settings.note_map,
            )
        )
        if not sound.start():
            sound = None
    try:
        code = serve(display, lambda endpoints: endpoints["sub"], {"settings": settings.summary()})
    finally:
        if sound is not None:
            sound.close()
    s = display.summary()
    where = ""
    if args.frames_dir:  # with --no-png the folder holds the frame log alone
        pngs = not getattr(args, "no_png", False)
        log = f"{args.frames_dir}/frames.jsonl"
        where = f" into {args.frames_dir}" if pngs else f", frame log in {log}"
    print(
        f"display: {s['frames']} frames{where}, {s['pose_samples']} pose samples, "
        f"{s['missing']} pose messages lost",
        file=sys.stderr,
    )
    if sound is not None and sound.stats is not None:
        print(sound.stats.line(), file=sys.stderr)
    return code


def practice_view(args: argparse.Namespace, ctx: Any, kit: Any, avatar: Any) -> Any:
    """``--practice``: the readout, and the teacher playing FILE animated offline (the file
    path ``render`` takes), for :mod:`services.display.practice_view`."""
    from livedrummer.errors import ConfigError
    from livedrummer.practice.teacher import parse_teacher

    from ..display.practice_view import PracticeView

    try:
        mode, ahead_s = parse_teacher(args.teacher)
    except ValueError as exc:
        raise ConfigError(f"--teacher {exc}") from None
    scene = None
    if mode != "off":
        if args.file is None:
            raise ConfigError("--teacher: give the reference FILE the teacher plays")
        performance, note_map = read_performance(args, Path(args.file), quiet=True)
        scene = body_scene(args, performance, kit, note_map, avatar)
    return PracticeView(ctx, args.practice, kit, mode, scene, ahead_s, avatar)  # type: ignore[arg-type]
