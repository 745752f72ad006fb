"""A stage of several drummers rendered to one video (``render --stage``).

Why this shape. The renderer draws one kit and one drummer around the seat at the origin,
lit by a key spot placed relative to that kit. A stage places N of them (the formations of
:mod:`livedrummer.stage.formation`), each turned by its yaw and moved to its spot. Rather
than teach the renderer several bodies, each drummer is drawn by its own
:class:`~services.display.renderer.Renderer` into a framebuffer of its own, seen by the
stage camera expressed in that drummer's own frame (the camera moved by the inverse of the
drummer's placement: a yaw about the vertical and a shift on the floor, so the view is the
same picture of that drummer standing at its spot). The N pictures are then merged pixel by
pixel by depth: the nearest surface wins, as if all had been drawn in one pass, and where no
drummer, kit or floor is drawn the background stays. Every drummer keeps its own key light
and shadows (as if each had a follow spot); the floors are one disc per drummer.

The stage camera is the single-kit camera of the same name (``stage``, ``front``, ...),
aimed at the group's centre and pulled back by the group's width, so the whole group fits.

Cost: N renders and a depth merge (one numpy pass) per frame; the sound is each drummer's
track mixed on its own kit and summed, scaled down as a whole only if it would clip.

Limits: one performer's shadow does not fall on another's kit; a drummer's floor disc may
show through a gap in another's (both are at floor level, the merge keeps either).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.audio.mix import fit_headroom, mix_onsets
from livedrummer.avatar.model import Avatar
from livedrummer.kit.model import Kit
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.scene import SceneFrame
from livedrummer.stage.formation import Placement
from livedrummer.timeline.performance import Performance

from .context import DisplayError, headless_context
from .export import ExportReport, frame_count, partial_path
from .png import write_png
from .record import spooled_track
from .renderer import Renderer
from .video import VideoSettings, VideoWriter, check_video_target

Progress = Callable[[int, int], None]
KIT_HALF_M = 1.6  # a five-piece kit with its drummer, from the seat to its outer cymbals


@dataclass(frozen=True)
class StageDrummer:
    """One drummer of the stage: its animated part, where it stands, who it is."""

    body: BodyScene
    performance: Performance
    placement: Placement
    avatar: Avatar | None = None


def group_camera(drummers: Sequence[StageDrummer], name: str, aspect: float) -> Camera:
    """The camera ``name`` of the first drummer's kit, aimed at the group's centre and pulled
    back until the group (each drummer with its kit, about :data:`KIT_HALF_M` around its
    spot) fits the frame's width and height as one kit fits the single-kit camera."""
    return group_camera_for(drummers[0].body.kit, [d.placement for d in drummers], name, aspect)


def group_camera_for(kit: Kit, placements: Sequence[Placement], name: str,
                     aspect: float) -> Camera:  # fmt: skip
    """:func:`group_camera` from the first kit and the spots alone (the live stage display)."""
    base = pick_camera(kit, name)
    xs = np.array([p.x for p in placements])
    ys = np.array([p.y for p in placements])
    centre = np.array([(xs.max() + xs.min()) / 2, (ys.max() + ys.min()) / 2, 0.0])
    offset = np.asarray(base.eye) - np.asarray(base.target)
    distance = float(np.linalg.norm(offset))
    half_v = math.tan(math.radians(base.fov_deg) / 2)
    # The group's half-extent across the view (its width seen from the camera's side) ...
    across = np.array([-offset[1], offset[0]]) / max(float(np.hypot(offset[0], offset[1])), 1e-9)
    spread = np.abs((xs - centre[0]) * across[0] + (ys - centre[1]) * across[1]).max()
    half_extent = float(spread) + KIT_HALF_M
    # ... fits the frame's width at the distance where one kit filled it
    needed = half_extent / (aspect * half_v)
    scale = max(1.0, needed / distance)
    target = np.asarray(base.target) + centre
    eye = target + offset * scale
    return Camera(f"{name} (stage of {len(placements)})", _vec(eye), _vec(target), base.fov_deg)


def local_camera(camera: Camera, placement: Placement) -> Camera:
    """``camera`` in the frame of a drummer placed at ``placement`` (see the docstring)."""
    a = math.radians(placement.yaw_deg)
    c, s = math.cos(a), math.sin(a)

    def inverse(p: tuple[float, float, float]) -> tuple[float, float, float]:
        x, y, z = p[0] - placement.x, p[1] - placement.y, p[2]
        return (c * x + s * y, -s * x + c * y, z)  # rotate by -yaw about +z

    return Camera(camera.name, inverse(camera.eye), inverse(camera.target), camera.fov_deg)


def _vec(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _track(drummers: Sequence[StageDrummer], seconds: float, sr: int) -> np.ndarray:
    """Every drummer's sounds on its own kit, summed (spooled on disk)."""
    n = round(seconds * sr)
    total = spooled_track(n)
    for d in drummers:
        own = spooled_track(n)
        mix_onsets(d.performance.onsets, seconds, d.body.kit, sr,
                   d.body.performed.sound_chokes, own)  # fmt: skip
        total += own
    fit_headroom(total)
    return total


def export_stage(
    drummers: Sequence[StageDrummer],
    *,
    out: Path | None,
    frames_dir: Path | None = None,
    settings: VideoSettings,
    camera: str = "stage",
    tail_s: float = 1.0,
    progress: Progress | None = None,
    background: Background | None = None,
) -> ExportReport:
    """Render the stage to ``out`` (MP4 with the summed drum track) and/or PNGs, in front of
    ``background`` (transparent: alpha 0 where no drummer, kit or floor is nearest)."""
    if not drummers:
        raise DisplayError("a stage needs at least one drummer")
    if out is None and frames_dir is None:
        raise DisplayError("nothing to write: give an output video or a frames folder")
    start = time.perf_counter()
    fps = settings.fps
    length = max(d.performance.duration_s for d in drummers) + tail_s
    n = frame_count(length, fps)
    times = np.arange(n) / fps
    if frames_dir is not None:
        frames_dir.mkdir(parents=True, exist_ok=True)
    writer: VideoWriter | None = None
    if out is not None:
        check_video_target(out, settings)
        audio = _track(drummers, n / fps, settings.sample_rate)
        writer = VideoWriter(partial_path(out), settings)
        writer.write_audio(audio)
    world = group_camera(drummers, camera, settings.size[0] / settings.size[1])
    alpha = background is not None and background.transparent
    ctx = None
    done = False
    try:
        ctx = headless_context()
        w, h = settings.size
        passes: list[tuple[Renderer, Any, Any, Camera, Iterator[SceneFrame]]] = []
        for d in drummers:
            renderer = Renderer(ctx, build_kit_mesh(d.body.kit), BODY_SKELETON, settings.size,
                                samples=0, avatar=d.avatar, background=background)  # fmt: skip
            depth = ctx.depth_texture((w, h))
            fbo = ctx.framebuffer(color_attachments=[ctx.texture((w, h), 4)],
                                  depth_attachment=depth)  # fmt: skip
            cam = local_camera(world, d.placement)
            passes.append((renderer, fbo, depth, cam, d.body.frames(times)))
        for i in range(n):
            colours, depths = [], []
            for renderer, fbo, _depth, cam, frames in passes:
                renderer.draw(next(frames), cam, target=fbo)
                colours.append(np.frombuffer(fbo.read(components=4), np.uint8).reshape(h, w, 4))
                depths.append(np.frombuffer(fbo.read(components=1, attachment=-1, dtype="f4"),
                                            np.float32).reshape(h, w))  # fmt: skip
            rgba = merge_by_depth(colours, depths)  # bottom row first, as GL reads
            if writer is not None:
                writer.write(rgba)
            if frames_dir is not None:
                top_down = rgba[::-1] if alpha else rgba[::-1, :, :3]
                write_png(frames_dir / f"frame_{i:06d}.png", np.ascontiguousarray(top_down))
            if progress is not None:
                progress(i + 1, n)
        done = True
    finally:
        if writer is not None:
            writer.close()
            if done and out is not None:
                os.replace(writer.path, out)
        if ctx is not None:
            ctx.release()
    return ExportReport(n, n / fps, time.perf_counter() - start)


def merge_by_depth(colours: Sequence[np.ndarray], depths: Sequence[np.ndarray]) -> np.ndarray:
    """Per pixel, the colour of the layer whose depth is nearest (the first on a tie)."""
    nearest = np.argmin(np.stack(depths), axis=0)
    stack = np.stack(colours)
    out: np.ndarray = np.take_along_axis(stack, nearest[None, :, :, None], axis=0)[0]
    return np.ascontiguousarray(out)
