"""``livedrummer demo``: the whole pipeline on the bundled groove, ending in something to watch.

It prints what the groove holds (as ``inspect`` does) and how the limbs were assigned, then
shows the drummer: in a window where there is a screen (``DISPLAY`` or ``WAYLAND_DISPLAY``
set), otherwise as a video, ``out/demo.mp4`` at 1280x720 with its drum track, reporting where
it is and how long it took. ``--seconds S`` keeps only the first S seconds (the whole groove,
about 88 s, takes a couple of minutes on a CPU); ``--render`` makes the video even with a
screen.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from pathlib import Path

from livedrummer.cli.common import DEMO_MAP, Subparsers, add_command, demo_groove
from livedrummer.cli.inspect import print_summary
from livedrummer.cli.render import ProgressBar, first_seconds
from livedrummer.midifile import read_midi_file
from livedrummer.notemap import load_note_map
from livedrummer.sticking.result import Sticking

DEMO_VIDEO = Path("out/demo.mp4")
DEMO_SIZE = (1280, 720)
DEMO_FPS = 30


def register(sub: Subparsers) -> None:
    p = add_command(sub, "demo", run, "run the pipeline on the bundled demo groove and show it")
    p.add_argument("--seconds", type=float, metavar="S", help="only the first S seconds")
    p.add_argument("--render", action="store_true", help="make the video even with a screen")
    p.add_argument("-o", "--output", type=Path, default=DEMO_VIDEO,
                   help=f"video file (default {DEMO_VIDEO})")  # fmt: skip


def sticking_line(st: Sticking) -> str:
    """One line: strategy and how many onsets each limb plays."""
    from livedrummer.sticking.result import LIMBS

    counts = Counter(int(v) for v in st.limb.tolist())
    parts = [f"{limb.value} {counts.get(i, 0)}" for i, limb in enumerate(LIMBS)]
    missed = sum(n for k, n in counts.items() if k < 0)
    return f"  sticking  {st.strategy}: {', '.join(parts)}, not played {missed}"


def has_screen() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def run(args: argparse.Namespace) -> int:
    from livedrummer.kitfile import load_kit
    from livedrummer.render.body_scene import BodyScene
    from livedrummer.render.camera import CAMERA_NAMES

    groove = demo_groove()
    note_map = load_note_map(DEMO_MAP)
    performance = read_midi_file(groove, note_map)
    if args.seconds is not None:
        performance = first_seconds(performance, args.seconds)
    print(f"demo: {groove.name} (Groove MIDI Dataset, CC BY 4.0)")
    print_summary(performance.summary())
    kit = load_kit("rock5")
    body = BodyScene.perform(performance, kit, note_map)
    print(sticking_line(body.performed.sticking))
    if has_screen() and not args.render:
        from services.display.window import show

        show(performance, kit, body=body)
        return 0
    from services.display.export import export
    from services.display.video import VideoSettings

    out: Path = args.output
    out.parent.mkdir(parents=True, exist_ok=True)
    settings = VideoSettings(size=DEMO_SIZE, fps=DEMO_FPS)
    print(f"no screen: rendering {performance.duration_s:.0f} s to {out} "
          f"({DEMO_SIZE[0]}x{DEMO_SIZE[1]} @ {DEMO_FPS} fps, camera {CAMERA_NAMES[0]})",
          flush=True)  # fmt: skip
    bar = ProgressBar("demo", True, DEMO_FPS, every_s=0.2 if sys.stderr.isatty() else 10.0)
    start = time.perf_counter()
    report = export(performance, body, out=out, settings=settings, camera=CAMERA_NAMES[0],
                    progress=bar)  # fmt: skip
    took = time.perf_counter() - start
    print(f"demo: wrote {out.resolve()} ({report.duration_s:.1f} s of video with sound) "
          f"in {took:.1f} s ({report.realtime:.2f}x real time)")  # fmt: skip
    return 0
