"""``livedrummer display FILE.mid``: play a MIDI file in a window (or full screen on a projector).

Keys: space play/pause, left/right step a frame, shift+left/right seek 5 s, home/end, r
reverse, +/- speed, 0 normal speed, m set a marker, [ ] previous/next marker, 1..8 cameras
(stage, front, drummer, overhead, left, right, back, kick), q or Esc quit. On a machine with
no screen use ``livedrummer render``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from livedrummer.cli.common import DEMO_MAP, Subparsers, add_command, add_kit_option, demo_groove
from livedrummer.cli.render import parse_size
from livedrummer.render.camera import CAMERA_NAMES


def register(sub: Subparsers) -> None:
    p = add_command(sub, "display", run, "play a MIDI file in a window with transport keys")
    p.add_argument("file", nargs="?", help="Standard MIDI File (default: the demo groove)")
    add_kit_option(p)
    p.add_argument("--map", help="note map (default general-midi; roland-td for the demo)")
    p.add_argument("--camera", default="stage", choices=CAMERA_NAMES, help="first viewpoint")
    p.add_argument("--size", default="1280x720", help="window size WIDTHxHEIGHT")
    p.add_argument("--fullscreen", action="store_true", help="full screen (projectors)")
    p.add_argument("--monitor", type=int, default=0, help="monitor index for --fullscreen")
    p.add_argument("--aa", type=int, default=4, metavar="N", help="multisample N (default 4)")
    p.add_argument("--quit-after", type=float, metavar="S", help="close after S seconds")


def run(args: argparse.Namespace) -> int:
    from livedrummer.kitfile import load_kit
    from livedrummer.midifile import read_midi_file
    from livedrummer.notemap import load_note_map
    from services.display.window import WindowOptions, show

    source = Path(args.file) if args.file else demo_groove()
    map_name = args.map or ("general-midi" if args.file else DEMO_MAP)
    performance = read_midi_file(source, load_note_map(map_name))
    options = WindowOptions(
        size=parse_size(args.size), fullscreen=args.fullscreen, monitor=args.monitor,
        camera=args.camera, samples=args.aa, quit_after_s=args.quit_after,
    )  # fmt: skip
    show(performance, load_kit(args.kit), options)
    return 0
