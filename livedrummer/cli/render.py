"""``livedrummer render FILE.mid -o out.mp4``: the performance as a video with its drum sounds.

Off-screen (EGL; Mesa llvmpipe where there is no GPU), so it works over SSH and in CI. Without
FILE it renders the bundled demo groove with the Roland map. The progress bar goes to stderr
and only when stderr is a terminal; the summary line goes to stdout.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

from livedrummer.cli.common import DEMO_MAP, Subparsers, add_command, add_kit_option, demo_groove
from livedrummer.errors import LivedrummerError
from livedrummer.render.camera import CAMERA_NAMES


class RenderOptionError(LivedrummerError):
    """A malformed --size or --fps."""


def register(sub: Subparsers) -> None:
    p = add_command(sub, "render", run, "render a MIDI file to a video (MP4 with sound) or PNGs")
    p.add_argument("file", nargs="?", help="Standard MIDI File (default: the demo groove)")
    p.add_argument("-o", "--output", type=Path, help="video file (default: FILE's name .mp4)")
    p.add_argument("--frames", type=Path, metavar="DIR", help="write PNG frames to DIR instead")
    p.add_argument("--size", default="1280x720", help="WIDTHxHEIGHT, even (default 1280x720)")
    p.add_argument("--fps", type=int, default=60, help="frames per second (default 60)")
    p.add_argument("--camera", default="stage", choices=CAMERA_NAMES, help="viewpoint")
    add_kit_option(p)
    p.add_argument("--map", help="note map (default general-midi; roland-td for the demo)")
    p.add_argument("--tail", type=float, default=1.0, help="seconds after the last event")
    p.add_argument("--aa", type=int, default=0, metavar="N", help="multisample N (slow on CPU)")
    p.add_argument("--crf", type=int, default=20, help="H.264 quality, lower is better")
    p.add_argument("--preset", default="veryfast", help="x264 speed preset (default veryfast)")


def parse_size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"(\d+)x(\d+)", text.strip())
    if not m:
        raise RenderOptionError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x720")
    w, h = int(m.group(1)), int(m.group(2))
    if not (16 <= w <= 7680 and 16 <= h <= 4320) or w % 2 or h % 2:
        raise RenderOptionError(f"--size {text!r}: width and height must be even, 16..7680")
    return w, h


class ProgressBar:
    """One self-rewriting stderr line: bar, percent, frames, speed and time left."""

    def __init__(self, label: str, enabled: bool, fps: int) -> None:
        self.label, self.enabled, self.fps = label, enabled, fps
        self.start = time.perf_counter()
        self.last = 0.0

    def __call__(self, done: int, total: int) -> None:
        now = time.perf_counter()
        if not self.enabled or (now - self.last < 0.2 and done < total):
            return
        self.last = now
        elapsed = max(now - self.start, 1e-9)
        filled = int(30 * done / total)
        speed = done / self.fps / elapsed
        eta = (total - done) / max(done / elapsed, 1e-9)
        sys.stderr.write(
            f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {100 * done // total:3d}%"
            f"  {done}/{total} frames  {speed:4.2f}x real time  {eta:4.0f} s left "
        )
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def run(args: argparse.Namespace) -> int:
    from livedrummer.kitfile import load_kit
    from livedrummer.midifile import read_midi_file
    from livedrummer.notemap import load_note_map
    from services.display.export import export
    from services.display.video import VideoSettings

    size = parse_size(args.size)
    if not 1 <= args.fps <= 240:
        raise RenderOptionError(f"--fps {args.fps}: expected 1..240")
    source = Path(args.file) if args.file else demo_groove()
    map_name = args.map or ("general-midi" if args.file else DEMO_MAP)
    performance = read_midi_file(source, load_note_map(map_name))
    kit = load_kit(args.kit)
    out = args.output
    if out is None and args.frames is None:
        out = Path(source.stem + ".mp4")
    settings = VideoSettings(size=size, fps=args.fps, crf=args.crf, preset=args.preset)
    bar = ProgressBar("render", sys.stderr.isatty(), args.fps)
    report = export(
        performance, kit, out=out, frames_dir=args.frames, settings=settings,
        camera=args.camera, tail_s=args.tail, samples=args.aa, progress=bar,
    )  # fmt: skip
    where = ", ".join(str(p) for p in (out, args.frames) if p is not None)
    print(
        f"wrote {where}: {report.frames} frames, {report.duration_s:.2f} s, "
        f"{size[0]}x{size[1]} @ {args.fps} fps, camera {args.camera}, kit {kit.name}"
        f"{', drum track 48 kHz stereo' if out is not None else ''}; "
        f"{report.realtime:.2f}x real time"
    )
    return 0
