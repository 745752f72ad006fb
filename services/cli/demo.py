"""``livedrummer demo``: the whole pipeline on the bundled groove, ending in something to watch.

By default this is the live product: it prints what the groove holds (as ``inspect`` does),
then runs ``livedrummer up --demo``: the input daemon plays the groove into the pipeline as
if from a kit, the synthesizer assigns hands and strokes online and the display draws the
drummer on its clock. Where there is a screen (``DISPLAY`` or ``WAYLAND_DISPLAY`` set) that is
a window (Q quits); otherwise the headless display records the show, and its drum track, to
``out/demo.mp4`` (1280x720, 30 fps) and the demo says where it is. ``--seconds S`` sets how
long it plays (default 30; it runs in real time); ``--headless`` records even with a screen.

``--size``, ``--camera``, ``--kit`` and ``--map`` mean what they mean for ``up`` and
``render``.

``--offline`` is the offline twin: the same groove read as a file with full lookahead (the
sticking of :func:`livedrummer.sticking.stick_performance`, as ``livedrummer sticking`` prints
it), rendered to the same video as fast as the machine allows, or played in the file window
with transport keys. (``--file`` and ``--render`` are the former spellings of ``--offline``
and ``--headless``.)
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

from .devices import has_screen
from .files import DEMO_MAP, demo_groove
from .parsing import Subparsers, add_command, add_renamed
from .performer import add_kit_option

if TYPE_CHECKING:
    from livedrummer.sticking.result import Sticking

DEMO_VIDEO = Path("out/demo.mp4")
DEMO_SIZE = (1280, 720)
DEMO_FPS = 30
LIVE_SECONDS = 30.0


def register(sub: Subparsers) -> None:
    p = add_command(sub, "demo", run)
    p.add_argument(
        "--seconds",
        type=float,
        metavar="S",
        help=f"play S s (default {LIVE_SECONDS:g}; --offline: the first S s, default all)",
    )
    add_renamed(
        p,
        "--file",
        p.add_argument("--offline", action="store_true", help="the groove as a file, not live"),
    )
    add_renamed(
        p,
        "--render",
        p.add_argument(
            "--headless", action="store_true", help="record the video even with a screen"
        ),
    )
    p.add_argument(
        "-o", "--output", type=Path, default=DEMO_VIDEO, help=f"video file (default {DEMO_VIDEO})"
    )
    p.add_argument(
        "--soundfont",
        type=Path,
        metavar="SF2",
        help="video: drum sounds from this General MIDI SoundFont (default: the built-in kit)",
    )
    p.add_argument(
        "--size",
        metavar="WxH",
        help=f"window or video size (default {DEMO_SIZE[0]}x{DEMO_SIZE[1]})",
    )
    p.add_argument(
        "--camera", metavar="NAME", help="viewpoint (default stage live, front --offline)"
    )
    add_kit_option(p)
    p.add_argument(
        "--map",
        default=DEMO_MAP,
        help=f"note map the groove is read with (default {DEMO_MAP}, the "
        "Groove MIDI Dataset's TD-11)",
    )
    p.add_argument(
        "--sfz",
        type=Path,
        metavar="SFZ",
        dest="soundfont",
        help="drum sounds from this SFZ sampled kit (instead of --soundfont; "
        "default: the built-in kit)",
    )


def sticking_line(st: Sticking) -> str:
    """One line: strategy and how many onsets each limb plays."""
    from livedrummer.sticking.result import LIMBS

    counts = Counter(int(v) for v in st.limb.tolist())
    parts = [f"{limb.value} {counts.get(i, 0)}" for i, limb in enumerate(LIMBS)]
    missed = sum(n for k, n in counts.items() if k < 0)
    return f"  sticking  {st.strategy}: {', '.join(parts)}, not played {missed}"


def run(args: argparse.Namespace) -> int:
    return run_file(args) if args.offline else run_live(args)


def run_live(args: argparse.Namespace) -> int:
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    from . import build_parser
    from .inspect import print_summary
    from .up import run as up

    groove = demo_groove()
    print(f"demo: {groove.name} (Groove MIDI Dataset, CC BY 4.0), played live into the pipeline")
    print_summary(read_midi_file(groove, load_note_map(args.map)).summary())
    seconds = LIVE_SECONDS if args.seconds is None else args.seconds
    argv = ["up", "--demo", "--seconds", f"{seconds:g}", "--kit", args.kit, "--map", args.map]
    if args.camera is not None:
        argv += ["--camera", args.camera]
    if has_screen() and not args.headless:
        print("demo: in a window (Q quits)", flush=True)
        if args.size is not None:
            argv += ["--size", args.size]
    else:
        out: Path = args.output
        size = args.size or f"{DEMO_SIZE[0]}x{DEMO_SIZE[1]}"
        print(
            f"demo: no screen: recording {seconds:g} s of the live show to {out} "
            f"({size} @ {DEMO_FPS} fps)",
            flush=True,
        )
        argv += [
            "--video",
            str(out),
            "--size",
            size,
            "--fps",
            str(DEMO_FPS),
            "--frames-dir",
            str(out.parent / "live"),
        ]
        if args.soundfont is not None:
            argv += ["--soundfont", str(args.soundfont)]
    return up(build_parser(argv).parse_args(argv))


def run_file(args: argparse.Namespace) -> int:
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from livedrummer.render.body_scene import BodyScene
    from livedrummer.render.camera import CAMERA_NAMES

    from .inspect import print_summary
    from .render import ProgressBar, first_seconds, parse_size

    size = parse_size(args.size) if args.size else DEMO_SIZE
    camera = args.camera or CAMERA_NAMES[0]
    if camera not in CAMERA_NAMES:
        from .render import RenderOptionError

        raise RenderOptionError(f"--camera {camera!r}: expected one of {', '.join(CAMERA_NAMES)}")
    kit = load_kit(args.kit)
    groove = demo_groove()
    note_map = load_note_map(args.map)
    performance = read_midi_file(groove, note_map)
    if args.seconds is not None:
        performance = first_seconds(performance, args.seconds)
    print(f"demo: {groove.name} (Groove MIDI Dataset, CC BY 4.0)")
    print_summary(performance.summary())
    body = BodyScene.perform(performance, kit, note_map)
    print(sticking_line(body.performed.sticking))
    if has_screen() and not args.headless:
        from ..display.window import show

        show(performance, kit, body=body)
        return 0
    from ..display.export import export
    from ..display.video import VideoSettings

    out: Path = args.output
    out.parent.mkdir(parents=True, exist_ok=True)
    settings = VideoSettings(size=size, fps=DEMO_FPS)
    print(
        f"no screen: rendering {performance.duration_s:.0f} s to {out} "
        f"({size[0]}x{size[1]} @ {DEMO_FPS} fps, camera {camera}, kit {kit.name})",
        flush=True,
    )
    bar = ProgressBar("demo", True, DEMO_FPS, every_s=0.2 if sys.stderr.isatty() else 10.0)
    start = time.perf_counter()
    report = export(
        performance,
        body,
        out=out,
        settings=settings,
        camera=camera,
        progress=bar,
        soundfont=args.soundfont,
        jobs=None,
    )
    took = time.perf_counter() - start
    print(
        f"demo: wrote {out.resolve()} ({report.duration_s:.1f} s of video with sound) "
        f"in {took:.1f} s ({report.realtime:.2f}x real time)"
    )
    return 0
