"""The practice rig's drummers: the player's avatar driven live and the teacher, in a window.

``livedrummer practice REF --virtual Kit`` shows, where there is a screen (``DISPLAY`` or
``WAYLAND_DISPLAY``), the player's drummer driven live through the pipeline ``up`` runs: an
input daemon owns the kit's port and publishes its hits, a synth turns them into poses, a live
display draws them; each a process, started in order after the one before said it is ready and
restarted when it dies (:mod:`services.process.supervisor`). The rig itself subscribes to the input
daemon's stream (:mod:`services.practice.bus`) and judges the hits with their driver stamps, as
when it reads the port itself, and sends the display its readout and plans
(:mod:`services.practice.readout_out`), from which the display draws the readout and moves the
teacher (``--teacher ghost``, ``ahead[:SECONDS]`` or ``off``;
:mod:`services.display.practice_view`). ``--headless`` renders off screen into ``--frames-dir``
(``--png`` writes every frame, ``--video FILE.mp4`` records them, as ``up`` does);
``--no-window`` is the terminal-only rig (the rig opens the port itself; for scripts). With no
screen and none of these, the rig is terminal-only and says so in one line.

Settings: the take's map (``--take-map``), the kit, the avatar and D are resolved once
(:func:`show_settings`) for the rig's own loop, the recording's drum track and the three
processes, which are given them as one file (``--settings``, :mod:`.settings`).

Endpoints: TCP ports ``--port-base`` .. +3 on loopback (the input's stream and control, the
synth's poses and control); the readout's port is the system's pick.

The recording (``--video``) gets a drum track when the session is over: the player's hits in
the kit's sounds and the click, at their time + D (:data:`SHOW_DELAY_MS`, the synth's delay)
on the video's time (:mod:`services.practice.recording`).

Limits: the display's frames follow the monotonic clock headless and the audio clock in a
window, as ``up``'s do.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .devices import has_screen
from .performer import add_avatar_option, add_kit_option
from .picture import add_look_option
from .settings import write_settings

if TYPE_CHECKING:
    from livedrummer.live.settings import ShowSettings

    from ..process.supervisor import Supervisor

SHOW_SUBSCRIBERS = 2  # the synth and the rig subscribe to the input daemon's stream
#: D: the synth shows a hit this long after its stamp (``up``'s default); the recording's drum
#: track sounds it then.
SHOW_DELAY_MS = 30.0


def add_show_options(p: argparse.ArgumentParser) -> None:
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--no-window",
        action="store_true",
        help="no drummers: the terminal readout only (scripts); the default without a screen",
    )
    where.add_argument(
        "--headless",
        action="store_true",
        help="draw the drummers off screen into --frames-dir (and --video)",
    )
    p.add_argument(
        "--teacher",
        default="ghost",
        metavar="MODE",
        help="the reference's drummer: ghost (translucent, in the player's drummer, "
        "where the sticks should be now), ahead[:SECONDS] (an inset beside it, "
        "SECONDS ahead; default 0.5) or off (default ghost)",
    )
    add_kit_option(p)
    add_avatar_option(p)
    add_look_option(p)
    p.add_argument(
        "--frames-dir",
        type=Path,
        default=Path("out/practice"),
        metavar="DIR",
        help="--headless: frames.jsonl (and --png frames) here (default out/practice)",
    )
    p.add_argument("--png", action="store_true", help="--headless: also write every frame as PNG")
    p.add_argument(
        "--video",
        type=Path,
        metavar="FILE",
        help="--headless: record the drummers and the readout as MP4 (default: none)",
    )
    p.add_argument(
        "--size", help="frame size WIDTHxHEIGHT (default 1280x720 in a window, 640x360 headless)"
    )
    p.add_argument("--fps", type=float, default=30.0, help="display frames per second")
    p.add_argument(
        "--port-base",
        type=int,
        default=5750,
        help="TCP ports PORT..PORT+3 on loopback (default 5750)",
    )


def show_mode(args: argparse.Namespace) -> str:
    """``window``, ``headless`` or ``none`` (see the module docstring)."""
    if args.no_window:
        return "none"
    if args.headless or args.video is not None:
        return "headless"
    return "window" if has_screen() else "none"


def check_show(args: argparse.Namespace, mode: str) -> None:
    """The options of the drummers checked before anything starts: one line, exit 2."""
    from livedrummer.errors import ConfigError
    from livedrummer.practice.teacher import parse_teacher

    from .performer import avatar_of
    from .render import parse_size

    try:
        parse_teacher(args.teacher)
    except ValueError as exc:
        raise ConfigError(f"--teacher {exc}") from None
    if mode == "none":
        return
    if not 0 < args.fps <= 240:
        raise ConfigError(f"--fps: expected 0 < fps <= 240 (got {args.fps:g})")
    if not 0 < args.port_base <= 65535 - 3:
        raise ConfigError(f"--port-base: expected 1..65532 (got {args.port_base})")
    parse_size(frame_size(args, mode))
    avatar_of(args)


def show_settings(args: argparse.Namespace) -> ShowSettings:
    """The rig's settings, resolved once for the practice loop, its input daemon, synth and
    display (:mod:`.settings`): the take's map (``--take-map``), the kit, the avatar, D =
    :data:`SHOW_DELAY_MS` with the synth's default lookahead; the display sounds nothing.
    The practice loop loads the map (one line when it is bad) before anything starts."""
    from livedrummer.live.settings import AvatarChoice, Delay, ShowSettings, spec_path

    bone_map = None if args.bone_map is None else str(args.bone_map)
    return ShowSettings(
        note_map=spec_path(args.take_map) or args.take_map,
        kit=spec_path(args.kit) or args.kit,
        avatar=AvatarChoice(spec_path(args.avatar), spec_path(bone_map), args.fit),
        delay=Delay(delay_s=SHOW_DELAY_MS / 1000.0),
    )


def frame_size(args: argparse.Namespace, mode: str) -> str:
    return str(args.size or ("1280x720" if mode == "window" else "640x360"))


def specs(args: argparse.Namespace, mode: str, readout: str, settings: Path) -> list[Any]:
    """The input, synth and display of the rig (see the module docstring), each given the
    ``settings`` file (:func:`show_settings`)."""
    from ..process.program import program_argv
    from ..process.supervisor import ServiceSpec

    base = args.port_base
    ep = [f"tcp://127.0.0.1:{base + k}" for k in range(4)]
    me = program_argv()
    if args.serial is not None:
        source = ["--serial", args.serial, "--baud", str(args.baud)]
    elif args.virtual is not None:
        source = ["--virtual", args.virtual, "--api", args.api]
    else:
        source = ["--midi", args.midi, "--api", args.api]
    given = ["--settings", str(settings)]
    input_argv = [*me, "input", *source, *given, "--pub", ep[0],
                  "--control", ep[1], "--wait-subscribers", str(SHOW_SUBSCRIBERS),
                  "--no-journal"]  # fmt: skip
    synth_argv = [*me, "synth", "--sub", ep[0], "--pub", ep[2], "--control", ep[3], *given]
    display_argv = [*me, "display", "--live", "--sub", ep[2], *given,
                    "--fps", str(args.fps), "--size", frame_size(args, mode),
                    "--practice", readout, "--teacher", args.teacher,
                    str(args.reference), "--map", args.map]  # fmt: skip
    display_argv += ["--channel", args.channel] if args.channel is not None else []
    display_argv += ["--look", args.look] if args.look else []
    if mode == "window":
        display_argv += ["--aa", "0"]
    else:
        display_argv += ["--headless", "--frames-dir", str(args.frames_dir)]
        display_argv += [] if args.png else ["--no-png"]
        display_argv += ["--video", str(args.video)] if args.video is not None else []
    # the rig's stdout is its own (--json lines): the services print theirs on stderr
    return [
        ServiceSpec("input", input_argv, stdout_to_stderr=True),
        ServiceSpec("synth", synth_argv, stdout_to_stderr=True),
        ServiceSpec("display", display_argv, ends_rig=mode == "window", stdout_to_stderr=True),
    ]


def add_drum_track(
    settings: ShowSettings, args: argparse.Namespace, hits: Any, clicks: list[tuple[Any, Any]]
) -> str:
    """Mux the drum track into ``args.video`` (see the module docstring), with the kit, map
    and D the rig's processes were given (``settings``); a line saying so."""
    import numpy as np

    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map

    from ..display.record import Timing, mux_audio
    from ..practice.recording import practice_track

    timing = Timing.load(args.video)
    times = np.concatenate([t for t, _ in clicks] or [np.zeros(0)])
    accents = np.concatenate([a for _, a in clicks] or [np.zeros(0, bool)])
    delay_s = settings.delay.delay_s
    track = practice_track(
        hits,
        times,
        accents,
        timing,
        delay_s=delay_s,
        kit=load_kit(settings.kit),
        note_map=load_note_map(settings.note_map),
        click_sound=args.click_sound,
        click_level=args.click_level,
    )
    mux_audio(args.video, track)
    duration = timing.frames / timing.fps
    shown = hits["time_s"].astype(np.float64) + delay_s - timing.show0_s
    heard = int(np.count_nonzero((shown >= 0.0) & (shown < duration)))
    return (
        f"practice: wrote {args.video} ({duration:.1f} s, {heard} hits and the click in "
        f"its drum track)"
    )


class Show:
    """The running drummers: the supervisor, the rig's onset subscription and readout stream."""

    def __init__(self, args: argparse.Namespace, mode: str, settings: ShowSettings) -> None:
        import tempfile

        import zmq

        from ..practice.bus import OnsetBus
        from ..practice.readout_out import ReadoutOut
        from ..process.supervisor import Supervisor

        self.mode = mode
        self.ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        self.readout = ReadoutOut(self.ctx)
        self.bus = OnsetBus(self.ctx, f"tcp://127.0.0.1:{args.port_base}")
        self._folder = tempfile.TemporaryDirectory(prefix="livedrummer-practice-")
        given = write_settings(settings, Path(self._folder.name))
        self.sup: Supervisor = Supervisor(specs(args, mode, self.readout.endpoint, given))
        if mode == "headless":
            args.frames_dir.mkdir(parents=True, exist_ok=True)

    def start(self) -> None:
        self.sup.start()

    def tick(self, now_s: float) -> bool:
        """Supervise (restarts) and send plans again; False once the window was closed."""
        self.sup.run_once(0.0)
        self.readout.tick(now_s)
        return not (self.mode == "window" and self.sup.quit_by_user("display"))

    def close(self) -> None:
        self.sup.stop()
        self.readout.close()
        self.ctx.destroy(0)
        self._folder.cleanup()
