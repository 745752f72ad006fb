"""Headless export: a performance to an MP4 with sound, or to numbered PNG frames.

One function, :func:`export`, does the whole job: it makes the EGL context and the renderer,
mixes the drum track (:func:`livedrummer.audio.mix.mix_onsets`, or with ``soundfont``
:func:`livedrummer.audio.soundfont.render_soundfont`) to exactly the video's length, with the
cuts of :attr:`~livedrummer.body.perform.Performed.sound_chokes` (a grab stops the sound where
it stops the cymbal, the pedal closing stops the ringing hi-hat, as the live sound does),
then renders frame ``i`` at ``t = i / fps`` and hands it to the encoder thread or the PNG
writer. The video gets each frame as I420, converted to YUV on the GPU, where the
width is a multiple of 8 (other widths: RGBA, converted on the encoder thread); the PNGs get
RGB (RGBA with a transparent background, whose video keeps its alpha: see
:mod:`.video`). The drummer and the kit's motion come from a
:class:`~livedrummer.render.body_scene.BodyScene` (the body model), sampled in chunks of frames
as the render goes, and the drum track is mixed on disk
(:func:`~services.display.record.spooled_track`), so memory stays bounded however long the
file.

The frames are drawn by a :class:`FramePainter`, in this process or (``jobs`` > 1, ``render
--jobs``) in worker processes, each with its own context and renderer, which hand them back in
frame order (:mod:`.parallel`); the encoder thread and the PNG names are the same either way,
and so are the frames.

The frame count is ``ceil((performance.duration_s + tail_s) * fps)`` and the audio track is
exactly that many frames long, so video and audio durations agree to the sample.

The video is written as ``NAME.part.EXT`` and renamed to ``NAME.EXT`` once the last frame is
in, so the target name only ever holds a whole render; an interrupted render (Ctrl-C, an
error) closes the part file properly, so what was rendered stays watchable there, and says
so. A kill -9 leaves the part file unfinished, never the target.

Overlays (SMED's scrolling score, the joint-angle graph; :mod:`livedrummer.render.overlay`) are
painted with numpy per frame and blended over the drawn frame before it is read back.
"""

from __future__ import annotations

import logging
import math
import os
import resource
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.audio.kitfile import render_kit_file
from livedrummer.audio.mix import mix_onsets
from livedrummer.avatar.model import Avatar
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.lights import LightRig
from livedrummer.render.overlay import OverlayModels
from livedrummer.render.overlay_raster import overlay_image
from livedrummer.timeline.performance import Performance

from .context import DisplayError, headless_context
from .parallel import frame_stream
from .png import write_png
from .record import spooled_track
from .renderer import Renderer, i420_ok
from .showctl import darken
from .video import VideoSettings, VideoWriter, check_video_target

log = logging.getLogger("livedrummer.render")

Progress = Callable[[int, int], None]
DEFAULT_SETTINGS = VideoSettings()


@dataclass(frozen=True)
class ExportReport:
    frames: int
    duration_s: float
    wall_s: float

    @property
    def realtime(self) -> float:
        """Seconds of video made per second of wall-clock time."""
        return self.duration_s / self.wall_s if self.wall_s > 0 else math.inf


def partial_path(out: Path) -> Path:
    """Where a render is written until it is whole: ``NAME.part.EXT`` beside ``NAME.EXT``."""
    return out.with_name(f"{out.stem}.part{out.suffix}")


def frame_count(duration_s: float, fps: int) -> int:
    return max(1, math.ceil(duration_s * fps - 1e-9))


def export(
    performance: Performance,
    body: BodyScene,
    *,
    out: Path | None,
    frames_dir: Path | None = None,
    settings: VideoSettings = DEFAULT_SETTINGS,
    camera: str = "stage",
    tail_s: float = 1.0,
    samples: int = 0,
    progress: Progress | None = None,
    overlays: frozenset[str] = frozenset(),
    soundfont: Path | None = None,
    avatar: Avatar | None = None,
    span: tuple[float, float] | None = None,
    background: Background | None = None,
    fxaa: bool = False,
    staging: Callable[[float], tuple[Camera, float]] | None = None,
    lights: LightRig | None = None,
    lighting: Callable[[float], LightRig] | None = None,
    jobs: int | None = 1,
) -> ExportReport:
    """Render ``performance`` to ``out`` (MP4) and/or PNGs in ``frames_dir``, with the
    overlay strips ``overlays`` (names of :data:`~livedrummer.render.overlay.OVERLAYS`); the
    drum track from the SoundFont ``soundfont`` when given, else the built-in kit; behind the
    stage ``background`` (transparent: RGBA PNGs and a video with alpha).

    ``span`` = (start_s, end_s) renders only that part (``render --start/--end``): frame ``i``
    shows ``start_s + i / fps``, the motion is the whole performance's (strokes that begin
    before the cut are already in the air), and the track is the whole mix's slice, so a
    cymbal struck before the cut still rings into it. ``staging``: each frame's camera and
    darkness by its time (a cue list's :class:`~livedrummer.live.cues.CuedStage`), instead
    of ``camera``; ``lighting``: each frame's lights by its time (asked after ``staging``,
    which fires the cues), instead of ``lights``. ``jobs``: worker processes drawing the frames
    (None: one a core; :mod:`.parallel`), the same frames as one process draws."""
    if out is None and frames_dir is None:
        raise DisplayError("nothing to write: give an output video or a frames folder")
    start, cpu0 = time.perf_counter(), process_cpu_s()
    fps = settings.fps
    first_s, end_s = span if span is not None else (0.0, performance.duration_s + tail_s)
    n = frame_count(end_s - first_s, fps)
    times = first_s + np.arange(n) / fps
    kit = body.kit
    cam = pick_camera(kit, camera)
    if frames_dir is not None:
        try:
            frames_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise DisplayError(f"cannot make frames folder {frames_dir}: {exc.strerror}") from None
    painter = FramePainter(
        body,
        cam,
        settings.size,
        times,
        frames_dir,
        samples=samples,
        avatar=avatar,
        background=background,
        fxaa=fxaa,
        lights=lights,
        overlays=overlays,
        end_s=first_s + n / fps,
        video=out is not None,
        staging=staging,
        lighting=lighting,
    )
    # forked now, before the sound is mixed: the workers build their renderers meanwhile
    stream = frame_stream(painter, n, jobs)
    writer: VideoWriter | None = None
    done = False
    try:
        if out is not None:
            writer = _open_writer(performance, body, out, settings, first_s, n, soundfont)
        for i, image in enumerate(stream):
            if writer is not None and image is not None:
                writer.write(image)
            if progress is not None:
                progress(i + 1, n)
        done = True
    finally:
        stream.close()
        if writer is not None:
            writer.close()  # also on Ctrl-C: what was rendered stays watchable, as .part
            if done and out is not None:
                os.replace(writer.path, out)  # the target name only ever holds a whole render
            else:
                log.warning(
                    "render stopped after %d of %d frames: they are in %s",
                    writer.frames,
                    n,
                    writer.path,
                )
    wall_s = time.perf_counter() - start
    log.info(
        "render: %.2f s of CPU here, %.2f s in %d workers, %.2f s wall",
        process_cpu_s() - cpu0,
        sum(stream.cpu_s),
        stream.workers,
        wall_s,
    )
    return ExportReport(n, n / fps, wall_s)


def process_cpu_s() -> float:
    """This process's CPU seconds so far, every thread's (user + system)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _open_writer(
    performance: Performance,
    body: BodyScene,
    out: Path,
    settings: VideoSettings,
    first_s: float,
    n: int,
    soundfont: Path | None,
) -> VideoWriter:
    """The part file's writer with the whole drum track already in (see :func:`export`)."""
    fps = settings.fps
    lead = round(first_s * settings.sample_rate)
    length = round(n / fps * settings.sample_rate)
    track = spooled_track(lead + length)
    mixed_s = (lead + length) / settings.sample_rate
    if soundfont is not None:  # before the writer: a bad file leaves no empty video
        audio = render_kit_file(
            performance.onsets,
            mixed_s,
            soundfont,
            settings.sample_rate,
            body.kit,
            body.performed.sound_chokes,
            track,
        )
    else:
        audio = mix_onsets(
            performance.onsets,
            mixed_s,
            body.kit,
            settings.sample_rate,
            body.performed.sound_chokes,
            track,
        )
    check_video_target(out, settings)
    writer = VideoWriter(partial_path(out), settings)
    writer.write_audio(audio[lead:])
    return writer


class FramePainter:
    """Draws the frames of an export (:data:`~.parallel.DrawFrames`): its own EGL context
    and renderer, made when called, so each worker process has its own. Frames it is not
    asked for are only uploaded, never drawn: the face's reactions
    (:class:`~livedrummer.body.face.FaceTrack`) follow every frame in time order, so a frame
    looks the same whichever worker draws it."""

    def __init__(
        self,
        body: BodyScene,
        camera: Camera,
        size: tuple[int, int],
        times: np.ndarray,
        frames_dir: Path | None,
        *,
        samples: int,
        avatar: Avatar | None,
        background: Background | None,
        fxaa: bool,
        lights: LightRig | None,
        overlays: frozenset[str],
        end_s: float,
        video: bool,
        staging: Callable[[float], tuple[Camera, float]] | None,
        lighting: Callable[[float], LightRig] | None = None,
    ) -> None:
        self.lighting = lighting
        self.body, self.camera, self.size, self.times = body, camera, size, times
        self.frames_dir, self.samples, self.avatar = frames_dir, samples, avatar
        self.background, self.fxaa, self.lights = background, fxaa, lights
        self.overlays, self.staging, self.end_s = overlays, staging, end_s
        self.alpha = background is not None and background.transparent
        self.video = video  # False: the frames go to PNGs only

    def __call__(self, wanted: np.ndarray) -> Iterator[np.ndarray | None]:
        if not wanted.size:
            return
        mine = np.zeros(int(wanted[-1]) + 1, bool)
        mine[wanted] = True
        ctx = headless_context()
        try:
            renderer = Renderer(
                ctx,
                build_kit_mesh(self.body.kit),
                BODY_SKELETON,
                self.size,
                samples=self.samples,
                avatar=self.avatar,
                background=self.background,
                fxaa=self.fxaa,
                lights=self.lights,
            )
            gpu_yuv = i420_ok(self.size) and not self.alpha
            times = self.times
            strips = overlay_image(self.size, self.overlays, OverlayModels(self.body, self.end_s))
            for i, frame in enumerate(self.body.frames(times[: mine.size])):
                if not mine[i]:
                    renderer.upload(frame)  # followed, not drawn (see the class docstring)
                    yield None
                    continue
                t = float(times[i])
                if self.staging is None:
                    renderer.draw(frame, self.camera)
                else:
                    view, dark = self.staging(t)
                    if self.lighting is not None:
                        renderer.lights = self.lighting(t)
                    renderer.draw(frame, view)
                    darken(renderer, dark)
                if not strips.empty:
                    r = strips.rect
                    renderer.draw_overlay(strips.paint(t), (r.x, r.y, r.width, r.height))
                if self.frames_dir is not None:
                    pixels = renderer.read_rgba_top() if self.alpha else renderer.read_rgb()
                    write_png(self.frames_dir / f"frame_{i:06d}.png", pixels)
                if not self.video:
                    yield None
                else:
                    yield renderer.read_i420() if gpu_yuv else renderer.read_rgba()
        finally:
            ctx.release()
