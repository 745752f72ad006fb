"""``livedrummer export FILE.mid -o out.bvh``: the drummer's motion as a BVH file.

Animates the file on the kit, with the limbs :func:`livedrummer.sticking.stick_performance`
gives (``--sticking``, ``--score``: what ``livedrummer sticking`` prints), and samples it at
``--fps`` from the first onset minus a second to the last plus a second.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from livedrummer.errors import LivedrummerError

from .common import (
    Subparsers,
    add_command,
    add_kit_option,
    add_map_option,
    add_motion_options,
    sticking_of,
)


def register(sub: Subparsers) -> None:
    p = add_command(sub, "export", run)
    p.add_argument("file", help="Standard MIDI File")
    p.add_argument("-o", "--output", required=True, help="output .bvh path")
    p.add_argument("--fps", type=float, default=60.0, help="frames per second (default 60)")
    add_kit_option(p)
    add_map_option(p)
    add_motion_options(p)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.body.bvh import bvh_text
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.rig import build_rig
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    if not 1.0 <= args.fps <= 1000.0:
        raise LivedrummerError(f"--fps must be between 1 and 1000 (got {args.fps})")
    note_map = load_note_map(args.map)
    kit = load_kit(args.kit)
    rig = build_rig(kit)
    performance = read_midi_file(args.file, note_map)
    expression = load_expression(args.preset) if args.preset else None
    done = perform(
        performance,
        rig,
        note_map,
        expression,
        StrokeParams(model=args.strokes),
        sticking=sticking_of(args, performance, kit),
    )
    t = performance.onsets["time_s"]
    start = max(0.0, float(t.min()) - 1.0) if t.size else 0.0
    end = float(t.max()) + 1.0 if t.size else 1.0
    times = np.arange(start, end, 1.0 / args.fps)
    local, root = done.animation.locals(times)
    out = Path(args.output)
    try:
        out.write_text(bvh_text(rig.skeleton, local, root, args.fps))
    except OSError as exc:
        raise LivedrummerError(f"{out}: cannot write: {exc.strerror or exc}") from exc
    print(f"{out}: {times.size} frames at {args.fps:g} fps, {len(local[0])} joints")
    return 0
