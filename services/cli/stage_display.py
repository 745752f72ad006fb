"""``display --live --stage FILE --sub EP1,EP2,...``: the live stage display (not a subcommand).

The stage file says who stands where on which kit; ``--sub`` lists the pose endpoints of the
performers that play live (those with a ``source``), one per performer in the file's order
(``up --stage`` passes them). With ``--settings F1,F2,...`` (one per ``--sub``, as ``up
--stage`` resolved each performer's, :mod:`.settings`) each drummer's kit, avatar and fitting
come from its file; without, from the stage file, fitted as each synth fits them (``--fit
auto``). The display is :class:`services.display.stage_live.StageDisplay`.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from livedrummer.avatar.model import Avatar
    from livedrummer.kit.model import Kit

    from ..display.live import FrameClock


def run_stage_live(args: argparse.Namespace) -> int:
    from livedrummer.errors import ConfigError
    from livedrummer.live.calibration import Calibration
    from livedrummer.stage.stagefile import load_stage

    from ..display.stage_live import StageConfig, StageDisplay, StagePerformer
    from ..process.service import serve
    from .keys import security_from_args
    from .picture import lights_of
    from .render import parse_size
    from .staging import check_room

    stage = load_stage(args.stage)
    check_room(stage)
    live = stage.live()
    subs = [s.strip() for s in args.sub.split(",") if s.strip()]
    if len(subs) != len(live):
        names = ", ".join(p.id if p.copy == 0 else f"{p.id}.{p.copy}" for _, p, _ in live)
        raise ConfigError(
            f"--sub: {len(subs)} endpoints for {len(live)} live performers of "
            f"{args.stage} ({names}): give one each, in that order"
        )
    if not 0 < args.fps <= 1000:
        raise ConfigError(f"--fps: expected 0 < fps <= 1000 (got {args.fps})")
    if args.max_frames is not None and args.max_frames < 1:
        raise ConfigError(f"--max-frames: expected >= 1 (got {args.max_frames})")
    if args.seconds is not None and not args.seconds > 0:
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    window = None
    if not args.headless:
        from ..display.window import WindowOptions

        if args.video is not None or args.frames_dir is not None:
            raise ConfigError(
                "display --live --stage: --video and --frames-dir record off screen: add --headless"
            )
        window = WindowOptions(
            size=parse_size(args.size),
            fullscreen=args.fullscreen,
            monitor=args.monitor,
            camera=args.camera,
            samples=0,
            vsync=False,
        )
    if args.settings is not None:
        played = _played_as_given(args, len(live))
    else:
        played = _played_from_stage(live)
    performers = [
        StagePerformer(p.id if p.copy == 0 else f"{p.id}.{p.copy}", k, sub, kit, spot, avatar)
        for (k, p, spot), sub, (kit, avatar) in zip(live, subs, played, strict=True)
    ]
    calibration = Calibration.load()
    config = StageConfig(
        fps=args.fps,
        size=parse_size(args.size),
        camera=args.camera,
        frames=args.max_frames,
        seconds=args.seconds,
        out=args.frames_dir,
        png=not args.no_png,
        video=args.video,
        window=window,
        render=not args.no_render,
        display_offset_s=calibration.display_ms / 1000.0,
        security=security_from_args(args),
        control=args.control,
        # the first live performer's kit's [lights] under the stage file's, under --look
        lights=lights_of(args, played[0][0], stage),
    )
    import zmq

    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    clock = _clock(args, window is not None, calibration.audio_ms)
    display = StageDisplay(performers, config, clock, ctx)
    code = serve(display, lambda endpoints: ",".join(p.sub for p in performers))
    s = display.summary()
    where = f" into {args.frames_dir}" if args.frames_dir else ""
    each = "; ".join(
        f"{name}: {v['pose_samples']} pose samples, {v['missing']} lost, "
        f"{v['bad']} bad, {v['restarts']} restarts"
        for name, v in s["performers"].items()
    )
    print(f"display: {s['frames']} stage frames{where}; {each}", file=sys.stderr)
    return code


def _played_as_given(args: argparse.Namespace, count: int) -> list[tuple[Kit, Avatar | None]]:
    """Each drummer's kit and avatar from its settings file (``--settings``, one per
    ``--sub``); copies of a performer share one file, loaded once."""
    from pathlib import Path

    from livedrummer.errors import ConfigError
    from livedrummer.live.settings import ShowSettings

    from .settings import played_by

    files = [f.strip() for f in str(args.settings).split(",") if f.strip()]
    if len(files) != count:
        raise ConfigError(
            f"--settings: {len(files)} files for {count} live performers of "
            f"{args.stage}: give one each, in --sub's order"
        )
    done: dict[str, tuple[Kit, Avatar | None]] = {}
    for f in files:
        if f not in done:
            done[f] = played_by(ShowSettings.load(Path(f)))
    return [done[f] for f in files]


def _played_from_stage(live: list[Any]) -> list[tuple[Kit, Avatar | None]]:
    """Each drummer's kit and avatar as the stage file names them, fitted as its synth fits
    them (``--fit auto``)."""
    from livedrummer.avatar.fit import fit_avatar
    from livedrummer.kit.loader import load_kit

    avatars = {}
    if any(p.avatar for _, p, _ in live):
        from livedrummer.avatar.loader import load_avatar

        avatars = {p.id: load_avatar(p.avatar) for _, p, _ in live if p.avatar is not None}
    kits = {p.kit: load_kit(p.kit) for _, p, _ in live}
    fits = {p.id: fit_avatar(kits[p.kit], avatars[p.id]) for _, p, _ in live if p.id in avatars}
    return [
        (fits[p.id].kit, fits[p.id].avatar) if p.id in fits else (kits[p.kit], None)
        for _, p, _ in live
    ]


def _clock(args: argparse.Namespace, windowed: bool, audio_ms: float) -> FrameClock:
    """``--clock``, as for one drummer: a window follows the audio output where there is one."""
    import logging

    from ..display.context import DisplayError
    from ..display.live import AudioFrameClock, MonotonicFrameClock

    if args.clock == "audio" or (args.clock == "auto" and windowed):
        try:
            return AudioFrameClock(audio_ms / 1000.0)
        except DisplayError as exc:
            if args.clock == "audio":
                raise
            logging.getLogger("livedrummer.display").warning(
                "%s: frames on the monotonic clock", exc
            )
    return MonotonicFrameClock(audio_ms / 1000.0)
