"""``livedrummer render FILE.mid -o out.mp4``: the performance as a video with its drum sounds.

Off-screen (EGL; Mesa llvmpipe where there is no GPU), so it works over SSH and in CI. Without
FILE it renders the bundled demo groove with the Roland map. The drummer is the body model
(:mod:`livedrummer.body`) playing the limbs :func:`livedrummer.sticking.stick_performance`
gives, as ``livedrummer sticking`` prints them; ``--sticking``, ``--score``, ``--strokes`` and
``--preset`` mean what they mean for ``livedrummer check`` (the x264 speed preset is
``--x264-preset``). ``--frames-dir DIR`` writes PNG frames instead of the video. The progress
bar goes to stderr and only when stderr is a terminal; the summary line goes to stdout.
``--start``/``--end`` render a part, in seconds or bars (:mod:`livedrummer.timeline.span`).
``--overlay score,joints`` adds SMED's scrolling score and the joint-angle graph as strips at
the bottom of the frame. ``--soundfont FILE.sf2`` plays the drum track with that General MIDI
SoundFont's kit (FluidSynth, :mod:`livedrummer.audio.soundfont`) instead of the built-in one.
``--background`` puts a colour, an image, chroma green or nothing (alpha: RGBA PNGs, or a
``.mov`` ProRes 4444 / ``.webm`` VP9 video with alpha, the default output then ``.mov``)
behind the stage. ``--jobs N`` draws the frames in N worker processes (default: one a core),
the same frames one process draws (:mod:`services.display.parallel`).
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.errors import LivedrummerError
from livedrummer.render.camera import CAMERA_NAMES
from livedrummer.render.frame_split import parse_jobs
from livedrummer.timeline.span import Position, parse_position, span_seconds

from .files import DEMO_MAP, add_channel_option, demo_groove, read_performance
from .parsing import Subparsers, add_command, add_renamed
from .performer import (
    add_avatar_option,
    add_kit_option,
    add_motion_options,
    avatar_of,
    fitted,
    rig_for,
    sticking_of,
)
from .picture import add_background_option, add_look_option, background_of, lights_of, parse_aa

if TYPE_CHECKING:
    from livedrummer.avatar.model import Avatar
    from livedrummer.kit.model import Kit
    from livedrummer.midi.notemap import NoteMap
    from livedrummer.render.body_scene import BodyScene
    from livedrummer.timeline.performance import Performance


class RenderOptionError(LivedrummerError):
    """A malformed --size or --fps."""


def register(sub: Subparsers) -> None:
    p = add_command(sub, "render", run)
    p.add_argument("file", nargs="?", help="Standard MIDI File (default: the demo groove)")
    p.add_argument("-o", "--output", type=Path, help="video file (default: FILE's name, .mp4)")
    add_renamed(
        p,
        "--frames",
        p.add_argument(
            "--frames-dir",
            type=Path,
            metavar="DIR",
            help="write PNG frames to DIR instead of a video (default: a video)",
        ),
    )
    p.add_argument("--size", default="1280x720", help="WIDTHxHEIGHT, even")
    p.add_argument("--fps", type=int, default=30, help="frames per second")
    p.add_argument("--camera", default="stage", choices=CAMERA_NAMES, help="viewpoint")
    add_kit_option(p)
    p.add_argument(
        "--map",
        help="note map name or .toml path (default auto: the bundled map "
        "that knows the most of the file's notes; roland-td for the demo)",
    )
    add_channel_option(p)
    p.add_argument("--tail", type=float, default=1.0, help="seconds after the last event")
    p.add_argument(
        "--start",
        metavar="POS",
        help="render from POS: seconds (12.5) or a bar's downbeat (bar5) (default: the beginning)",
    )
    p.add_argument(
        "--end",
        metavar="POS",
        help="render up to POS: seconds (40) or the end of a bar (bar8) "
        "(default: the last event plus --tail)",
    )
    p.add_argument(
        "--aa",
        default="fxaa",
        metavar="fxaa|N",
        help="anti-aliasing: fxaa (one cheap pass; default), 0 (none) or multisample "
        "N = 2, 4, 8 (about 2.7x the frame time on a CPU)",
    )
    p.add_argument("--crf", type=int, default=20, help="H.264 quality, lower is better")
    p.add_argument("--x264-preset", default="veryfast", help="x264 speed")
    p.add_argument(
        "--overlay",
        default="",
        metavar="LIST",
        help="bottom strips: score, joints or score,joints (default: none)",
    )
    p.add_argument(
        "--cues",
        type=Path,
        metavar="FILE",
        help="cue list (TOML): presets, parameters, camera and blackout at times or "
        "bars (default: none)",
    )
    p.add_argument(
        "--soundfont",
        type=Path,
        metavar="SF2",
        help="drum sounds from this General MIDI SoundFont via FluidSynth "
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
        "--jobs",
        default="auto",
        metavar="N|auto",
        help="worker processes drawing the frames, each its own OpenGL context "
        "(default auto: one a core; 1: this process alone)",
    )
    add_motion_options(p)
    add_avatar_option(p)
    p.add_argument(
        "--stage",
        type=Path,
        metavar="TOML",
        help="render every drummer of a stage file on one stage instead of FILE (default: none)",
    )
    add_background_option(p)
    add_look_option(p)


def body_scene(
    args: argparse.Namespace,
    performance: Performance,
    kit: Kit,
    note_map: NoteMap,
    avatar: Avatar | None = None,
) -> BodyScene:
    """The performance animated on ``kit`` with the motion options of ``args``, by a body with
    ``avatar``'s proportions (the built-in character's without one)."""
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.render.body_scene import BodyScene

    expression = load_expression(args.preset) if args.preset else None
    sticking = sticking_of(args, performance, kit)
    done = perform(
        performance,
        rig_for(kit, avatar),
        note_map,
        expression,
        StrokeParams(model=args.strokes),
        sticking=sticking,
    )
    return BodyScene(kit, done)


def cued(
    args: argparse.Namespace,
    performance: Performance,
    note_map: NoteMap,
    body: BodyScene,
    lights: Any = None,
) -> tuple[BodyScene, Any]:
    """``--cues``: the body with the cue list's style changes and the frames' stage (camera,
    blackout and lights by time, from ``lights``), a CuedStage; bars are counted on the
    file's grid."""
    from livedrummer.body.expression import Expression, load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.live.cues import CuedStage, cue_times, load_cues, style_changes
    from livedrummer.live.stage import Stage
    from livedrummer.render.cued import CuedBodyScene

    cues = load_cues(args.cues)
    grid = performance.grid
    timed = cue_times(cues, grid.beat_s[grid.beat_in_bar == 0])
    base = load_expression(args.preset) if args.preset else Expression()
    p = body.performed
    rig = p.animation.rig
    styled = tuple(
        (
            at,
            perform(
                performance,
                rig,
                note_map,
                expression,
                StrokeParams(model=args.strokes),
                sticking=p.sticking,
            ),
        )
        for at, expression in style_changes(timed, base)[1:]
    )
    scene = CuedBodyScene(body.kit, p, styled)
    print(
        f"livedrummer: {args.cues}: {len(timed)} timed cues ({len(styled)} change the style)",
        file=sys.stderr,
    )
    return scene, CuedStage(Stage(body.kit, args.camera, lights=lights), timed)


def first_seconds(performance: Performance, seconds: float) -> Performance:
    """The performance cut to its first ``seconds`` (onsets and controls before the cut)."""
    if seconds >= performance.duration_s:
        return performance
    return dataclasses.replace(
        performance,
        duration_s=max(seconds, 0.0),
        onsets=performance.onsets[performance.onsets["time_s"] < seconds],
        controls=performance.controls[performance.controls["time_s"] < seconds],
    )


def position_option(option: str, text: str | None) -> Position | None:
    """``--start``/``--end``'s text as a :class:`Position` (checked before the file is read)."""
    if text is None:
        return None
    try:
        return parse_position(text)
    except ValueError as exc:
        raise RenderOptionError(f"{option} {exc}") from None


def parse_size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"(\d+)x(\d+)", text.strip())
    if not m:
        raise RenderOptionError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x720")
    w, h = int(m.group(1)), int(m.group(2))
    if not (16 <= w <= 7680 and 16 <= h <= 4320) or w % 2 or h % 2:
        raise RenderOptionError(f"--size {text!r}: width and height must be even, 16..7680")
    return w, h


class ProgressBar:
    """Progress on stderr: one self-rewriting line on a terminal (every ``every_s``), else one
    plain line every ``every_s`` seconds. Bar, percent, frames, speed and time left."""

    def __init__(self, label: str, enabled: bool, fps: int, every_s: float = 0.2) -> None:
        self.label, self.enabled, self.fps, self.every_s = label, enabled, fps, every_s
        self.tty = sys.stderr.isatty()
        self.start = time.perf_counter()
        self.last = self.start if not self.tty else 0.0

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if not self.enabled or (now - self.last < self.every_s and done < total):
            return
        self.last = now
        elapsed = max(now - self.start, 1e-9)
        filled = int(30 * done / total)
        speed = done / self.fps / elapsed
        eta = (total - done) / max(done / elapsed, 1e-9)
        line = (
            f"{self.label} [{'#' * filled}{'.' * (30 - filled)}] {100 * done // total:3d}%"
            f"  {done}/{total} frames  {speed:4.2f}x real time  {eta:4.0f} s left "
        )
        if self.tty:
            sys.stderr.write("\r" + line + ("\n" if done == total else ""))
        else:
            sys.stderr.write(line.rstrip() + "\n")
        sys.stderr.flush()


def _start_workers_early(jobs: int | None) -> None:
    """``--jobs`` other than 1: the workers' fork server starts now, while the file is read
    and performed (:func:`services.display.parallel.start_server`)."""
    from livedrummer.render.frame_split import usable_cores

    if jobs != 1 and usable_cores() > 1:
        from ..display.parallel import start_server

        start_server()


def run(args: argparse.Namespace) -> int:
    if args.stage is not None:
        return run_stage(args)
    from livedrummer.kit.loader import load_kit
    from livedrummer.render.overlay import OVERLAYS, parse_overlays
    from livedrummer.sticking.strategy import get_strategy

    from ..display.export import export
    from ..display.video import VideoSettings, check_video_target

    size = parse_size(args.size)
    jobs = parse_jobs(args.jobs)
    samples, fxaa = parse_aa(args.aa)
    overlays = parse_overlays(args.overlay)
    if not 1 <= args.fps <= 240:
        raise RenderOptionError(f"--fps {args.fps}: expected 1..240")
    start_pos, end_pos = position_option("--start", args.start), position_option("--end", args.end)
    if args.soundfont is not None:
        from livedrummer.audio.kitfile import check_kit_file

        check_kit_file(args.soundfont)
    source = Path(args.file) if args.file else demo_groove()
    _start_workers_early(jobs)
    # Every option is checked before the file is read (and its report printed): a mistyped
    # option is the one line on stderr.
    kit, avatar = fitted(args, load_kit(args.kit), avatar_of(args))
    background = background_of(args)
    lights = lights_of(args, kit)
    get_strategy(args.sticking)
    if args.cues is not None:  # checked now, applied once the file is animated
        from livedrummer.live.cues import load_cues

        load_cues(args.cues)
    out = args.output
    if out is None and args.frames_dir is None:
        out = Path(source.stem + (".mov" if background.transparent else ".mp4"))
    settings = VideoSettings(
        size=size, fps=args.fps, crf=args.crf, preset=args.x264_preset, alpha=background.transparent
    )
    if out is not None:
        check_video_target(out, settings)
    performance, note_map = read_performance(args, source, "auto" if args.file else DEMO_MAP)
    if not performance.onsets.size:  # said on stderr: nothing for the drummer to play
        return 0
    span = None
    if start_pos is not None or end_pos is not None:
        try:
            span = span_seconds(
                start_pos, end_pos, performance.grid, performance.duration_s + args.tail
            )
        except ValueError as exc:
            raise RenderOptionError(f"{source}: --start/--end: {exc}") from None
    body = body_scene(args, performance, kit, note_map, avatar)
    staging = None
    if args.cues is not None:
        body, staging = cued(args, performance, note_map, body, lights)
    bar = ProgressBar("render", sys.stderr.isatty(), args.fps)
    report = export(
        performance,
        body,
        out=out,
        frames_dir=args.frames_dir,
        settings=settings,
        camera=args.camera,
        tail_s=args.tail,
        samples=samples,
        fxaa=fxaa,
        progress=bar,
        overlays=overlays,
        soundfont=args.soundfont,
        avatar=avatar,
        background=background,
        span=span,
        staging=None if staging is None else staging.at,
        lights=lights,
        lighting=None if staging is None else staging.lights_at,
        jobs=jobs,
    )
    where = ", ".join(str(p) for p in (out, args.frames_dir) if p is not None)
    print(
        f"wrote {where}: {report.frames} frames, {report.duration_s:.2f} s"
        f"{f' (from {span[0]:.2f} s to {span[1]:.2f} s)' if span else ''}, "
        f"{size[0]}x{size[1]} @ {args.fps} fps, camera {args.camera}, kit {kit.name}, "
        f"sticking {args.sticking}"
        f"{', overlay ' + ','.join(n for n in OVERLAYS if n in overlays) if overlays else ''}"
        f"{', drum track 48 kHz stereo' if out is not None else ''}"
        f"{' from ' + str(args.soundfont) if out is not None and args.soundfont else ''}"
        f"{', background ' + args.background if args.background else ''}, look {lights.name}; "
        f"{report.realtime:.2f}x real time"
    )
    return 0


def run_stage(args: argparse.Namespace) -> int:
    """``render --stage``: every drummer of the stage file, on one stage, in one video."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.stage.stagefile import load_stage

    from ..display.stage_export import StageDrummer, export_stage
    from ..display.video import VideoSettings, check_video_target
    from .staging import stage_parts

    if args.file:
        raise RenderOptionError("render: give a MIDI file or --stage, not both")
    size = parse_size(args.size)
    jobs = parse_jobs(args.jobs)
    if not 1 <= args.fps <= 240:
        raise RenderOptionError(f"--fps {args.fps}: expected 1..240")
    background = background_of(args)
    start_pos, end_pos = position_option("--start", args.start), position_option("--end", args.end)
    stage = load_stage(args.stage)
    _start_workers_early(jobs)
    out = args.output
    if out is None and args.frames_dir is None:
        out = Path(args.stage.stem + (".mov" if background.transparent else ".mp4"))
    settings = VideoSettings(
        size=size, fps=args.fps, crf=args.crf, preset=args.x264_preset, alpha=background.transparent
    )
    if out is not None:
        check_video_target(out, settings)
    # the first performer's kit's [lights] under the stage file's
    lights = lights_of(args, load_kit(stage.performers[0].kit), stage)
    drummers = []
    for part in stage_parts(stage, args):
        p = part.performer
        kit = load_kit(p.kit)
        own = argparse.Namespace(
            **{**vars(args), "preset": p.preset or args.preset, "avatar": p.avatar or args.avatar}
        )
        kit, avatar = fitted(own, kit, avatar_of(own))
        body = body_scene(own, part.performance, kit, part.note_map, avatar)
        drummers.append(StageDrummer(body, part.performance, part.placement, avatar))
    span = None
    if start_pos is not None or end_pos is not None:  # bars counted on the first part's grid
        length = max(d.performance.duration_s for d in drummers) + args.tail
        try:
            span = span_seconds(start_pos, end_pos, drummers[0].performance.grid, length)
        except ValueError as exc:
            raise RenderOptionError(f"{args.stage}: --start/--end: {exc}") from None
    bar = ProgressBar("render", sys.stderr.isatty(), args.fps)
    report = export_stage(
        drummers,
        out=out,
        frames_dir=args.frames_dir,
        settings=settings,
        camera=args.camera,
        tail_s=args.tail,
        progress=bar,
        background=background,
        span=span,
        lights=lights,
        jobs=jobs,
    )
    where = ", ".join(str(p) for p in (out, args.frames_dir) if p is not None)
    print(
        f"wrote {where}: {report.frames} frames, {report.duration_s:.2f} s"
        f"{f' (from {span[0]:.2f} s to {span[1]:.2f} s)' if span else ''}, "
        f"{len(drummers)} drummers ({stage.formation.shape}), {size[0]}x{size[1]} @ "
        f"{args.fps} fps, camera {args.camera}, look {lights.name}; "
        f"{report.realtime:.2f}x real time"
    )
    return 0
