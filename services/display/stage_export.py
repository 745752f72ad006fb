"""A stage of several drummers rendered to one video (``render --stage``).

Why this shape. The renderer draws one kit and one drummer around the seat at the origin,
lit by a key spot placed relative to that kit. A stage places N of them (the formations of
:mod:`livedrummer.stage.formation`), each turned by its yaw and moved to its spot. Rather
than teach the renderer several bodies, each drummer is drawn by its own
:class:`~services.display.renderer.Renderer`, seen by the stage camera expressed in that
drummer's own frame (the camera moved by the inverse of the drummer's placement: a yaw about
the vertical and a shift on the floor, so the view is the same picture of that drummer
standing at its spot). All N draw into ONE framebuffer (:class:`StagePainter`, which the live
stage display shares): the first clears it, the others draw over it with the depth test on,
so the nearest surface wins, as if all had been drawn in one pass, and where no drummer, kit
or floor is drawn the background stays. Every drummer keeps its own key light and shadows (as
if each had a follow spot). The floors are one disc per drummer on the same plane; each is
drawn only over its own cell (the floor points nearer to its pool of light than to any
other's, :mod:`livedrummer.stage.layout`): before that, overlapping discs fought pixel by pixel
(a depth tie between coplanar surfaces, decided by rounding), which showed as blocky black
jagged patches, one disc's shadowed or dark rim pixels winning over the other's lit pool.

The stage camera is the single-kit camera of the same name (``stage``, ``front``, ...), its
direction and field of view kept, moved so the group's kits are centred and fill the frame
(:func:`livedrummer.stage.layout.fit_group_camera`). ``span`` renders a part, as ``render``
does.

Cost: N renders and one read-back per frame; the sound is each drummer's track mixed on its own
kit and summed, scaled down as a whole only if it would clip.

Limits: one performer's shadow does not fall on another's kit, and ends at its floor cell's
edge; no anti-aliasing.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from livedrummer.audio.mix import fit_headroom, mix_onsets
from livedrummer.avatar.model import Avatar
from livedrummer.kit.model import Kit
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.lights import LightRig
from livedrummer.render.scene import SceneFrame
from livedrummer.stage.formation import Placement
from livedrummer.stage.layout import cell_neighbours, fit_group_camera, footprint, group_points
from livedrummer.timeline.performance import Performance

from .context import DisplayError, headless_context
from .export import ExportReport, frame_count, partial_path, process_cpu_s
from .parallel import frame_stream
from .png import write_png
from .record import spooled_track
from .renderer import Renderer
from .video import VideoSettings, VideoWriter, check_video_target

log = logging.getLogger(__name__)

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class StageDrummer:
    """One drummer of the stage: its animated part, where it stands, who it is."""

    body: BodyScene
    performance: Performance
    placement: Placement
    avatar: Avatar | None = None

    @property
    def kit(self) -> Kit:
        return self.body.kit


class Spot(Protocol):
    """What :class:`StagePainter` needs of a drummer: its kit, its spot, its avatar."""

    @property
    def kit(self) -> Kit: ...
    @property
    def placement(self) -> Placement: ...
    @property
    def avatar(self) -> Avatar | None: ...


class StagePainter:
    """N renderers drawing into one framebuffer (see the module docstring): the first clears
    it, the others draw over it depth-tested, which is the depth merge done by the GPU; each
    drummer's floor is cut to its cell (:func:`livedrummer.stage.layout.cell_neighbours`)."""

    def __init__(
        self,
        ctx: Any,
        drummers: Sequence[Spot],
        size: tuple[int, int],
        camera: str,
        target: Any = None,
        background: Background | None = None,
        lights: LightRig | None = None,
    ) -> None:
        self.ctx = ctx
        self.size = size
        w, h = size
        world = group_camera_for(
            [d.kit for d in drummers], [d.placement for d in drummers], camera, w / h
        )
        self.camera = world
        if target is None:
            target = ctx.framebuffer(
                color_attachments=[ctx.renderbuffer((w, h), 4)],
                depth_attachment=ctx.depth_renderbuffer((w, h)),
            )
        self.target = target
        self.passes: list[tuple[Renderer, Camera]] = []
        for d in drummers:
            renderer = Renderer(
                ctx,
                build_kit_mesh(d.kit),
                BODY_SKELETON,
                size,
                samples=0,
                offscreen=False,
                avatar=d.avatar,
                background=background,
                lights=lights,
            )
            self.passes.append((renderer, local_camera(world, d.placement)))
        cells = cell_neighbours(
            [d.placement for d in drummers], [r.pool_centre() for r, _c in self.passes]
        )
        for (renderer, _cam), others in zip(self.passes, cells, strict=True):
            renderer.floor_cell_others = others

    def draw(self, frames: Sequence[SceneFrame | None]) -> None:
        for k, ((renderer, cam), frame) in enumerate(zip(self.passes, frames, strict=True)):
            renderer.draw(frame, cam, target=self.target, clear=k == 0)

    def read_rgba(self) -> np.ndarray:
        """The frame drawn last, (H, W, 4) uint8, bottom row first (GL order)."""
        w, h = self.size
        data = self.target.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h, w, 4)


def group_camera(drummers: Sequence[StageDrummer], name: str, aspect: float) -> Camera:
    """The camera ``name`` of the first drummer's kit, moved to centre the group and fill the
    frame (:func:`livedrummer.stage.layout.fit_group_camera`: every drummer's kit box, floor to
    head height, seen whole)."""
    return group_camera_for(
        [d.body.kit for d in drummers], [d.placement for d in drummers], name, aspect
    )


def group_camera_for(
    kits: Kit | Sequence[Kit], placements: Sequence[Placement], name: str, aspect: float
) -> Camera:
    """:func:`group_camera` from the kits (one for all, or one per spot) and the spots alone
    (the live stage display)."""
    every = [kits] * len(placements) if isinstance(kits, Kit) else list(kits)
    prints = {id(k): footprint(k) for k in every}
    points = group_points(placements, [prints[id(k)] for k in every])
    base = pick_camera(every[0], name)
    return fit_group_camera(base, points, aspect, f"{name} (stage of {len(placements)})")


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
        mix_onsets(
            d.performance.onsets, seconds, d.body.kit, sr, d.body.performed.sound_chokes, own
        )
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
    span: tuple[float, float] | None = None,
    lights: LightRig | None = None,
    jobs: int | None = 1,
) -> ExportReport:
    """Render the stage to ``out`` (MP4 with the summed drum track) and/or PNGs, in front of
    ``background`` (transparent: alpha 0 where no drummer, kit or floor is nearest).

    ``span`` = (start_s, end_s) renders only that part, as :func:`.export.export` does
    (``render --stage --start/--end``): frame ``i`` shows ``start_s + i / fps``, every drummer's
    motion is its whole performance's and the track is the whole mix's slice. ``jobs``: worker
    processes drawing the frames (None: one a core; :mod:`.parallel`)."""
    if not drummers:
        raise DisplayError("a stage needs at least one drummer")
    if out is None and frames_dir is None:
        raise DisplayError("nothing to write: give an output video or a frames folder")
    start, cpu0 = time.perf_counter(), process_cpu_s()
    fps = settings.fps
    length = max(d.performance.duration_s for d in drummers) + tail_s
    first_s, end_s = span if span is not None else (0.0, length)
    n = frame_count(end_s - first_s, fps)
    times = first_s + np.arange(n) / fps
    if frames_dir is not None:
        frames_dir.mkdir(parents=True, exist_ok=True)
    if out is not None:
        check_video_target(out, settings)
    painter = StageFrames(
        drummers,
        settings.size,
        camera,
        times,
        frames_dir,
        background=background,
        lights=lights,
        video=out is not None,
    )
    stream = frame_stream(painter, n, jobs)  # forked before the mix: see export()
    writer: VideoWriter | None = None
    done = False
    try:
        if out is not None:
            lead = round(first_s * settings.sample_rate)
            length_n = round(n / fps * settings.sample_rate)
            audio = _track(drummers, (lead + length_n) / settings.sample_rate, settings.sample_rate)
            writer = VideoWriter(partial_path(out), settings)
            writer.write_audio(audio[lead:])
        for i, rgba in enumerate(stream):
            if writer is not None and rgba is not None:
                writer.write(rgba)
            if progress is not None:
                progress(i + 1, n)
        done = True
    finally:
        stream.close()
        if writer is not None:
            writer.close()
            if done and out is not None:
                os.replace(writer.path, out)
    wall_s = time.perf_counter() - start
    log.info(
        "render: %.2f s of CPU here, %.2f s in %d workers, %.2f s wall",
        process_cpu_s() - cpu0,
        sum(stream.cpu_s),
        stream.workers,
        wall_s,
    )
    return ExportReport(n, n / fps, wall_s)


class StageFrames:
    """Draws the frames of a stage export (:data:`~.parallel.DrawFrames`), its own context
    and :class:`StagePainter` made when called (one per worker process); frames it is not
    asked for are only uploaded, as :class:`~.export.FramePainter` does, so every drummer's
    face follows every frame."""

    def __init__(
        self,
        drummers: Sequence[StageDrummer],
        size: tuple[int, int],
        camera: str,
        times: np.ndarray,
        frames_dir: Path | None,
        *,
        background: Background | None,
        lights: LightRig | None,
        video: bool,
    ) -> None:
        self.drummers, self.size, self.camera, self.times = drummers, size, camera, times
        self.frames_dir, self.background, self.lights = frames_dir, background, lights
        self.video = video
        self.alpha = background is not None and background.transparent

    def __call__(self, wanted: np.ndarray) -> Iterator[np.ndarray | None]:
        if not wanted.size:
            return
        mine = np.zeros(int(wanted[-1]) + 1, bool)
        mine[wanted] = True
        ctx = headless_context()
        try:
            painter = StagePainter(
                ctx,
                self.drummers,
                self.size,
                self.camera,
                background=self.background,
                lights=self.lights,
            )
            frames = [d.body.frames(self.times[: mine.size]) for d in self.drummers]
            for i in range(mine.size):
                now = [next(f) for f in frames]
                if not mine[i]:
                    for (renderer, _cam), frame in zip(painter.passes, now, strict=True):
                        renderer.upload(frame)  # followed, not drawn
                    yield None
                    continue
                painter.draw(now)
                rgba = painter.read_rgba()  # bottom row first, as GL reads
                if self.frames_dir is not None:
                    top_down = rgba[::-1] if self.alpha else rgba[::-1, :, :3]
                    write_png(
                        self.frames_dir / f"frame_{i:06d}.png", np.ascontiguousarray(top_down)
                    )
                yield rgba if self.video else None
        finally:
            ctx.release()
