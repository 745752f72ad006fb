"""``livedrummer export FILE.mid -o out.bvh|out.glb``: the drummer's motion as BVH or glTF.

Animates the file on the kit, with the limbs :func:`livedrummer.sticking.stick_performance`
gives (``--sticking``, ``--score``: what ``livedrummer sticking`` prints), and samples it at
``--fps`` from the start of the file to its end plus ``--tail`` (default 1 s), the same span
``render`` and ``display`` show. A file with no drum notes writes nothing and says so.

``--format gltf`` (the default for a ``.glb`` output) writes the avatar (``--avatar``, else
the built-in character), its sticks and the motion as one binary glTF file with an animation
and the kit with its cymbals, hi-hat and beater moving (:mod:`livedrummer.avatar.gltf_export`);
BVH has the skeleton only. Both have the avatar's proportions.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from livedrummer.errors import LivedrummerError

from .files import add_channel_option, add_map_option, read_performance
from .parsing import Subparsers, add_command
from .performer import add_kit_option, add_motion_options, sticking_of


def register(sub: Subparsers) -> None:
    p = add_command(sub, "export", run)
    p.add_argument("file", help="Standard MIDI File")
    p.add_argument("-o", "--output", required=True, help="output .bvh or .glb path")
    p.add_argument(
        "--format",
        choices=("bvh", "gltf"),
        help="bvh (skeleton and motion) or gltf (binary .glb: avatar, sticks and "
        "motion) (default: from the output's suffix, .glb is gltf)",
    )
    p.add_argument("--fps", type=float, default=60.0, help="frames per second (default 60)")
    p.add_argument("--tail", type=float, default=1.0, help="seconds after the last event")
    add_kit_option(p)
    from .performer import add_avatar_option

    add_avatar_option(p)
    add_map_option(p)
    add_channel_option(p)
    add_motion_options(p)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.body.bvh import bvh_text
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.kit.loader import load_kit

    if not 1.0 <= args.fps <= 1000.0:
        raise LivedrummerError(f"--fps must be between 1 and 1000 (got {args.fps})")
    if not 0.0 <= args.tail <= 60.0:
        raise LivedrummerError(f"--tail must be between 0 and 60 s (got {args.tail})")
    performance, note_map = read_performance(args, args.file)
    if not performance.onsets.size:  # said on stderr: no motion to write
        return 0
    kit = load_kit(args.kit)
    from .performer import avatar_of, fitted, rig_for

    kit, avatar = fitted(args, kit, avatar_of(args))
    rig = rig_for(kit, avatar)
    expression = load_expression(args.preset) if args.preset else None
    done = perform(
        performance,
        rig,
        note_map,
        expression,
        StrokeParams(model=args.strokes),
        sticking=sticking_of(args, performance, kit),
    )
    # One length for every command: render and display show the file plus the same tail.
    end = max(performance.duration_s, float(performance.onsets["time_s"].max())) + args.tail
    times = np.arange(0.0, end, 1.0 / args.fps)
    local, root = done.animation.locals(times)
    out = Path(args.output)
    fmt = args.format or ("gltf" if out.suffix.lower() == ".glb" else "bvh")
    if fmt == "gltf" and out.suffix.lower() != ".glb":
        raise LivedrummerError(f"{out}: --format gltf writes binary glTF: name the file .glb")
    try:
        if fmt == "gltf":
            from livedrummer.avatar.character import build_character
            from livedrummer.avatar.gltf_export import performance_glb
            from livedrummer.render.body_scene import BodyScene, scene_channels
            from livedrummer.render.kitmesh import build_kit_mesh

            who = avatar if avatar is not None else build_character(rig.skeleton.lengths)
            channels = scene_channels(BodyScene(kit, done).poses(times), kit)
            kit_mesh = build_kit_mesh(kit, floor=False)
            data = performance_glb(who, rig.skeleton, times, local, root, kit_mesh, channels)
            out.write_bytes(data)
        else:
            out.write_text(bvh_text(rig.skeleton, local, root, args.fps))
    except OSError as exc:
        raise LivedrummerError(f"{out}: cannot write: {exc.strerror or exc}") from exc
    print(f"{out}: {times.size} frames at {args.fps:g} fps, {len(local[0])} joints")
    return 0
