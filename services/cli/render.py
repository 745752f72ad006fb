"""``livedrummer render FILE.mid -o out.mp4``: the performance as a video with its drum sounds.

Off-screen (EGL; Mesa llvmpipe where there is no GPU), so it works over SSH and in CI. Without
FILE it renders the bundled demo groove with the Roland map. The drummer is the body model
(:mod:`livedrummer.body`) playing the limbs :func:`livedrummer.sticking.stick_performance`
gives, as ``livedrummer sticking`` prints them; ``--sticking``, ``--score``, ``--strokes`` and
``--preset`` mean what they mean for ``livedrummer check`` (the x264 speed preset is
``--x264-preset``). ``--frames-dir DIR`` writes PNG frames instead of the video. The progress
bar goes to stderr and only when stderr is a terminal; the summary line goes to stdout.
``--overlay score,joints`` adds SMED's scrolling score and the joint-angle graph as strips at
the bottom of the frame. ``--soundfont FILE.sf2`` plays the drum track with that General MIDI
SoundFont's kit (FluidSynth, :mod:`livedrummer.audio.soundfont`) instead of the built-in one.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from livedrummer.errors import LivedrummerError
from livedrummer.render.camera import CAMERA_NAMES

from .common import (
    DEMO_MAP,
    Subparsers,
    add_avatar_option,
    add_channel_option,
    add_command,
    add_kit_option,
    add_motion_options,
    add_renamed,
    avatar_of,
    check_aa,
    demo_groove,
    read_performance,
    rig_for,
    sticking_of,
)

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
    p.add_argument("-o", "--output", type=Path,
                   help="video file (default: FILE's name, .mp4)")  # fmt: skip
    add_renamed(p, "--frames", p.add_argument(
        "--frames-dir", type=Path, metavar="DIR",
        help="write PNG frames to DIR instead of a video (default: a video)"))  # fmt: skip
    p.add_argument("--size", default="1280x720", help="WIDTHxHEIGHT, even")
    p.add_argument("--fps", type=int, default=30, help="frames per second")
    p.add_argument("--camera", default="stage", choices=CAMERA_NAMES, help="viewpoint")
    add_kit_option(p)
    p.add_argument("--map", help="note map name or .toml path (default auto: the bundled map "
                   "that knows the most of the file's notes; roland-td for the demo)")  # fmt: skip
    add_channel_option(p)
    p.add_argument("--tail", type=float, default=1.0, help="seconds after the last event")
    p.add_argument("--aa", type=int, default=0, metavar="N",
                   help="multisample N: 0, 2, 4 or 8 (slow on CPU; default 0)")  # fmt: skip
    p.add_argument("--crf", type=int, default=20, help="H.264 quality, lower is better")
    p.add_argument("--x264-preset", default="veryfast", help="x264 speed")
    p.add_argument("--overlay", default="", metavar="LIST",
                   help="bottom strips: score, joints or score,joints (default: none)")  # fmt: skip
    p.add_argument("--soundfont", type=Path, metavar="SF2",
                   help="drum sounds from this General MIDI SoundFont via FluidSynth "
                   "(default: the built-in kit)")  # fmt: skip
    p.add_argument("--sfz", type=Path, metavar="SFZ", dest="soundfont",
                   help="drum sounds from this SFZ sampled kit (instead of --soundfont; "
                   "default: the built-in kit)")  # fmt: skip
    add_motion_options(p)
    add_avatar_option(p)


def body_scene(args: argparse.Namespace, performance: Performance, kit: Kit, note_map: NoteMap,
               avatar: Avatar | None = None) -> BodyScene:  # fmt: skip
    """The performance animated on ``kit`` with the motion options of ``args``, by a body with
    ``avatar``'s proportions (the built-in character's without one)."""
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.render.body_scene import BodyScene

    expression = load_expression(args.preset) if args.preset else None
    sticking = sticking_of(args, performance, kit)
    done = perform(performance, rig_for(kit, avatar), note_map, expression,
                   StrokeParams(model=args.strokes), sticking=sticking)  # fmt: skip
    return BodyScene(kit, done)


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


def run(args: argparse.Namespace) -> int:
    from livedrummer.kit.loader import load_kit
    from livedrummer.render.overlay import OVERLAYS, parse_overlays
    from livedrummer.sticking.strategy import get_strategy

    from ..display.export import export
    from ..display.video import VideoSettings, check_video_target

    size = parse_size(args.size)
    check_aa(args.aa)
    overlays = parse_overlays(args.overlay)
    if not 1 <= args.fps <= 240:
        raise RenderOptionError(f"--fps {args.fps}: expected 1..240")
    if args.soundfont is not None:
        from livedrummer.audio.kitfile import check_kit_file

        check_kit_file(args.soundfont)
    source = Path(args.file) if args.file else demo_groove()
    # Every option is checked before the file is read (and its report printed): a mistyped
    # option is the one line on stderr.
    kit = load_kit(args.kit)
    avatar = avatar_of(args)
    get_strategy(args.sticking)
    out = args.output
    if out is None and args.frames_dir is None:
        out = Path(source.stem + ".mp4")
    settings = VideoSettings(size=size, fps=args.fps, crf=args.crf, preset=args.x264_preset)
    if out is not None:
        check_video_target(out, settings)
    performance, note_map = read_performance(args, source, "auto" if args.file else DEMO_MAP)
    if not performance.onsets.size:  # said on stderr: nothing for the drummer to play
        return 0
    body = body_scene(args, performance, kit, note_map, avatar)
    bar = ProgressBar("render", sys.stderr.isatty(), args.fps)
    report = export(
        performance, body, out=out, frames_dir=args.frames_dir, settings=settings,
        camera=args.camera, tail_s=args.tail, samples=args.aa, progress=bar, overlays=overlays,
        soundfont=args.soundfont, avatar=avatar,
    )  # fmt: skip
    where = ", ".join(str(p) for p in (out, args.frames_dir) if p is not None)
    print(
        f"wrote {where}: {report.frames} frames, {report.duration_s:.2f} s, "
        f"{size[0]}x{size[1]} @ {args.fps} fps, camera {args.camera}, kit {kit.name}, "
        f"sticking {args.sticking}"
        f"{', overlay ' + ','.join(n for n in OVERLAYS if n in overlays) if overlays else ''}"
        f"{', drum track 48 kHz stereo' if out is not None else ''}"
        f"{' from ' + str(args.soundfont) if out is not None and args.soundfont else ''}; "
        f"{report.realtime:.2f}x real time"
    )
    return 0
