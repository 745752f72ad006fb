"""Show-look benchmark: how much of each default camera's frame is lit, and how dark the rest.

Renders the demo groove (optimal sticking, the built-in character or ``--avatar``) at a few
times from the ``front``, ``stage`` and ``drummer`` cameras, once per ``--looks`` theme
(:data:`livedrummer.render.lights.LOOKS`), and prints per camera the median over the times of
the lit share (pixels above luma 0.1, :func:`livedrummer.render.litshare.lit_share`), the
subject's share (pixels the drummer and the kit cover: a second render without the floor on a
transparent background) and the mean luma outside the subject (floor and hall,
:func:`~livedrummer.render.litshare.background_luma`). The figures are of frames, not of
time, so nothing is alternated; ``--save DIR`` writes each frame as a PNG to look at.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

import numpy as np

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.background import parse_background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import kit_cameras
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.lights import LightRig, look_rig
from livedrummer.render.litshare import background_luma, hall_luma, lit_share

from ..cli.files import DEMO_MAP, demo_groove
from ..cli.performer import rig_for
from ..cli.render import parse_size
from ..display.context import headless_context
from ..display.png import write_png
from ..display.renderer import Renderer


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench look")
    parser.add_argument("--size", default="1280x720")
    parser.add_argument("--cameras", default="front,stage,drummer")
    parser.add_argument("--times", default="3.0,6.5,10.0", help="seconds into the groove")
    parser.add_argument(
        "--looks", default="", help="themes, e.g. concert,studio (default: the renderer's own)"
    )
    parser.add_argument("--avatar", default=None, help="a .vrm/.glb file (default: built-in)")
    parser.add_argument("--kit", default="rock5")
    parser.add_argument("--save", type=Path, default=None, help="write the frames as PNGs here")
    args = parser.parse_args(argv)

    avatar = None
    if args.avatar:
        from livedrummer.avatar.loader import load_avatar

        avatar = load_avatar(args.avatar)
    kit = load_kit(args.kit)
    note_map = load_note_map(DEMO_MAP)
    perf = read_midi_file(demo_groove(), note_map)
    from livedrummer.body.perform import perform

    body = BodyScene(kit, perform(perf, rig_for(kit, avatar), note_map))
    times = np.array([float(t) for t in args.times.split(",")])
    frames = list(body.frames(times))
    size = parse_size(args.size)
    looks = [v for v in args.looks.split(",") if v] or [""]
    if args.save is not None:
        args.save.mkdir(parents=True, exist_ok=True)
    ctx = headless_context()
    print(
        f"render: {ctx.info['GL_RENDERER']}, {args.size}, kit {args.kit}, "
        f"avatar {args.avatar or 'built-in'}, times {args.times} s"
    )
    bare = Renderer(
        ctx,
        build_kit_mesh(kit, floor=False),
        BODY_SKELETON,
        size,
        samples=0,
        avatar=avatar,
        background=parse_background("transparent"),
    )
    for look in looks:
        r = Renderer(
            ctx,
            build_kit_mesh(kit),
            BODY_SKELETON,
            size,
            samples=0,
            avatar=avatar,
            fxaa=True,
            lights=_look(look) if look else None,
        )
        for name in args.cameras.split(","):
            cam = kit_cameras(kit, avatar.lengths if avatar is not None else None)[name]
            lit, subj, back, hall = [], [], [], []
            for t, frame in zip(times, frames, strict=True):
                r.draw(frame, cam)
                rgb = r.read_rgb()
                bare.draw(frame, cam)
                mask = bare.read_rgba_top()[..., 3] > 0
                lit.append(lit_share(rgb))
                subj.append(float(mask.mean()))
                back.append(background_luma(rgb, mask))
                hall.append(hall_luma(rgb, mask))
                if args.save is not None:
                    write_png(args.save / f"{look or 'default'}-{name}-{t:05.1f}s.png", rgb)
            print(
                f"  look {look or 'default':>8}  {name:>8}: lit {statistics.median(lit):5.1%}"
                f"  subject {statistics.median(subj):5.1%}"
                f"  background luma {statistics.median(back):.3f}"
                f"  hall luma {statistics.median(hall):.3f}"
            )
    ctx.release()
    return 0


def _look(name: str) -> LightRig:
    return look_rig(name)
