"""Overlay benchmark: ms per frame of the score and joint-angle strips, headless.

On the demo groove (optimal sticking) at ``--size`` (1280x720): ``models`` is the one-off cost
of the score model and of sampling the six joint angles at 60 Hz over the whole performance;
``paint`` is the numpy rasterizer per frame (both strips, models sliced at the frame's time);
``upload+draw`` is :meth:`Renderer.draw_overlay` (texture write and the blended pass) with
``glFinish``; ``frame`` is draw + overlay + finish against draw + finish alone, so their
difference is what the overlay adds to a rendered frame. Medians over ``--frames`` frames.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.overlay import OVERLAYS, OverlayModels
from livedrummer.render.overlay_raster import overlay_image

from ..cli.files import DEMO_MAP, demo_groove
from ..cli.render import parse_size
from ..display.context import headless_context
from ..display.renderer import Renderer


def _ms(samples: list[float]) -> float:
    return 1e3 * statistics.median(samples)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="livedrummer bench overlay")
    p.add_argument("--size", default="1280x720")
    p.add_argument("--frames", type=int, default=120)
    args = p.parse_args(argv)
    size = parse_size(args.size)
    note_map = load_note_map(DEMO_MAP)
    performance = read_midi_file(demo_groove(), note_map)
    body = BodyScene.perform(performance, load_kit("rock5"), note_map)
    t0 = time.perf_counter()
    models = OverlayModels(body, performance.duration_s + 1.0)
    strips = overlay_image(size, frozenset(OVERLAYS), models)
    models_s = time.perf_counter() - t0
    r = strips.rect
    print(
        f"overlay {args.size}: strips {r.width}x{r.height} at y {r.y}; models "
        f"{models_s * 1e3:.1f} ms once ({len(models.angles.degrees)} angle samples, "
        f"{models.score().time_s.size} notes)"
    )
    times = np.linspace(2.0, performance.duration_s - 2.0, args.frames)
    ctx = headless_context()
    try:
        renderer = Renderer(ctx, build_kit_mesh(body.kit), BODY_SKELETON, size, samples=0)
        cam = pick_camera(body.kit, "stage")
        frames = list(body.frames(times))
        paint, upload, bare, full = [], [], [], []
        for t, frame in zip(times, frames, strict=True):
            renderer.draw(frame, cam)
            renderer.finish()
            t0 = time.perf_counter()
            image = strips.paint(float(t))
            paint.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            renderer.draw_overlay(image, (r.x, r.y, r.width, r.height))
            renderer.finish()
            upload.append(time.perf_counter() - t0)
        for t, frame in zip(times, frames, strict=True):
            t0 = time.perf_counter()
            renderer.draw(frame, cam)
            renderer.finish()
            bare.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            renderer.draw(frame, cam)
            renderer.draw_overlay(strips.paint(float(t)), (r.x, r.y, r.width, r.height))
            renderer.finish()
            full.append(time.perf_counter() - t0)
        print(f"  {ctx.info['GL_RENDERER']}")
    finally:
        ctx.release()
    print(
        f"  paint {_ms(paint):.3f} ms   upload+draw {_ms(upload):.3f} ms   "
        f"overlay total {_ms(paint) + _ms(upload):.3f} ms per frame"
    )
    print(
        f"  frame: draw {_ms(bare):.2f} ms, draw+overlay {_ms(full):.2f} ms "
        f"(+{_ms(full) - _ms(bare):.2f} ms)"
    )
    return 0
