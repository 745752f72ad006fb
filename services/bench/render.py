"""Render benchmark: ms per frame headless, with and without read-back, and export speed.

Draws the demo groove as the body model performs it (optimal sticking), from the ``stage``
camera; ``body`` is the time to sample the body's poses and map them to scene frames (per
frame, vectorized over all frames); ``avatar`` the time to generate the built-in character
(:func:`livedrummer.avatar.character.build_character`, median of 5), which every renderer
draws and skins on the GPU.
``draw`` is draw + ``glFinish`` (what a window pays before swapping); ``draw+read`` adds the
RGBA read-back of the frame into numpy, ``draw+i420`` the GPU conversion to YUV 4:2:0 and its
read-back (what export pays before encoding); ``pipelined`` issues all the frames' draws and
waits once at the end (the frame rate a GPU sustains when nothing stalls it on a finish).
Export speed is the whole ``livedrummer render`` job (audio mix, render, H.264/AAC encode)
on the first ``--seconds`` of the demo groove, as a multiple of real time. Medians of one run;
``--aa 0,fxaa,4`` measures no anti-aliasing, the FXAA pass and multisampling interleaved frame
by frame (export: the first).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from livedrummer.avatar.character import build_character
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import pick_camera
from livedrummer.render.kitmesh import build_kit_mesh

from ..cli.common import DEMO_MAP, demo_groove
from ..cli.render import first_seconds, parse_size
from ..display.context import headless_context
from ..display.export import export
from ..display.renderer import Renderer, i420_ok
from ..display.video import VideoSettings


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench render")
    parser.add_argument("--sizes", default="1280x720,1920x1080")
    parser.add_argument("--frames", type=int, default=120, help="frames per measurement")
    parser.add_argument("--aa", default="0",
                        help="multisample counts or fxaa, e.g. 0,fxaa,4: measured interleaved, "
                        "frame by frame, so each is loaded alike (default 0)")  # fmt: skip
    parser.add_argument("--seconds", type=float, default=20.0, help="export length (0: skip)")
    parser.add_argument("--export-fps", default="30,60")
    args = parser.parse_args(argv)

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    perf = read_midi_file(demo_groove(), note_map)
    t0 = time.perf_counter()
    body = BodyScene.perform(perf, kit, note_map)
    t1 = time.perf_counter()
    all_times = np.arange(int(perf.duration_s * 60)) / 60.0
    list(body.frames(all_times))
    t2 = time.perf_counter()
    print(
        f"body: perform {t1 - t0:.2f} s for {perf.duration_s:.0f} s of music; frames "
        f"{(t2 - t1) / all_times.size * 1e3:.3f} ms each ({all_times.size} at 60 fps)"
    )
    builds = []
    for _ in range(5):
        t0 = time.perf_counter()
        avatar = build_character()
        builds.append(time.perf_counter() - t0)
    print(f"avatar: built-in character {avatar.mesh.vertex_count} vertices, "
          f"{avatar.mesh.triangle_count} triangles, built in "
          f"{statistics.median(builds) * 1e3:.1f} ms")  # fmt: skip
    ctx = headless_context()
    counts = [v.strip() for v in args.aa.split(",")]  # multisample counts or "fxaa"
    print(f"render: {ctx.info['GL_RENDERER']} ({ctx.info['GL_VERSION']}), aa {args.aa}")
    cam = pick_camera(kit, "stage")
    times = np.arange(args.frames) / 60.0 + 4.0
    frames = list(body.frames(times))
    for text in args.sizes.split(","):
        size = parse_size(text)
        rs = [Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, avatar=avatar,
                       samples=0 if aa == "fxaa" else int(aa), fxaa=aa == "fxaa")
              for aa in counts]  # fmt: skip
        for r in rs:
            r.draw(frames[0], cam)
            r.read_rgba()
        draw: list[list[float]] = [[] for _ in rs]
        read: list[list[float]] = [[] for _ in rs]
        i420: list[list[float]] = [[] for _ in rs]
        for f in frames:  # interleaved: every renderer draws this frame before the next
            for k, r in enumerate(rs):
                t0 = time.perf_counter()
                r.draw(f, cam)
                ctx.finish()
                draw[k].append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                r.draw(f, cam)
                r.read_rgba()
                read[k].append(time.perf_counter() - t0)
                if i420_ok(size):
                    t0 = time.perf_counter()
                    r.draw(f, cam)
                    r.read_i420()
                    i420[k].append(time.perf_counter() - t0)
        for k, r in enumerate(rs):
            piped = []
            for _ in range(3):
                t0 = time.perf_counter()
                for f in frames:
                    r.draw(f, cam)
                ctx.finish()
                piped.append((time.perf_counter() - t0) / len(frames))
            d, rd = statistics.median(draw[k]) * 1e3, statistics.median(read[k]) * 1e3
            pd = statistics.median(piped) * 1e3
            yuv = f"   draw+i420 {statistics.median(i420[k]) * 1e3:6.2f} ms" if i420[k] else ""
            print(f"  {text:>9} aa {counts[k]:>4}  draw {d:6.2f} ms ({1e3 / d:6.1f} fps)   "
                  f"draw+read {rd:6.2f} ms ({1e3 / rd:6.1f} fps){yuv}   "
                  f"pipelined {pd:6.3f} ms ({1e3 / pd:7.1f} fps)")  # fmt: skip
    ctx.release()
    if args.seconds > 0:
        short = first_seconds(perf, args.seconds)
        short_body = BodyScene.perform(short, kit, note_map)
        with tempfile.TemporaryDirectory() as tmp:
            for fps in (int(v) for v in args.export_fps.split(",")):
                settings = VideoSettings(size=(1280, 720), fps=fps)
                report = export(short, short_body, out=Path(tmp) / "bench.mp4", settings=settings,
                                tail_s=0.0, samples=int(counts[0]) if counts[0].isdigit() else 0,
                                fxaa=counts[0] == "fxaa")  # fmt: skip
                print(f"  export 1280x720 @ {fps} fps: {report.frames} frames in "
                      f"{report.wall_s:.2f} s = {report.realtime:.2f}x real time")  # fmt: skip
    return 0
