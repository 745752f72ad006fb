"""The live stage display: every performer's synth, one picture (``display --live --stage``).

Streams. ``up --stage`` runs one synth per performer; this display subscribes to each of them
on its own SUB socket and keeps, per performer, its own
:class:`~services.display.pose_stream.PoseStream` (the live display's too: the receiver, a
:class:`~livedrummer.live.track.PoseTrack` and the counts): each stream numbers its messages
on its own, so a gap on one performer's stream is that stream's loss, counted for it, and a
restart of one performer's synth is seen on its stream alone.
The POSE header carries the performer id: a message whose id is not the one the stream was
opened for (a synth started with the wrong ``--performer``, or a miswired endpoint) is dropped
and counted as bad on that stream, never drawn on another drummer.

Drawing. As ``render --stage`` (:mod:`services.display.stage_export`), each drummer has its
own :class:`~services.display.renderer.Renderer` (its kit, its avatar, its key light and
shadow map) and the group camera (:func:`~services.display.stage_export.group_camera_for`)
is expressed in each drummer's frame; but live, the N drummers are drawn into ONE framebuffer:
the first clears it, the others draw over it with the depth test on, which is
``merge_by_depth`` done by the GPU (the same nearest-surface rule, no read-back of N colour
and depth pictures, no numpy pass: a 720p frame of 4 drummers took 211 ms instead of 445 ms,
p50, on a loaded 2-core machine). A frame is drawn for its show time (now + the frame
clock's latency + the measured render time, as the single-drummer display does); a drummer
with no pose yet is drawn as its empty kit, one whose stream stalls holds its last pose.
Headless, frames go to ``--frames-dir`` (``frames.jsonl``: per frame and per performer the
pose time drawn, the newest pose received and the kit pieces lit, i.e. the contacts seen;
PNGs unless ``png`` is off) and to a video on show time (frames repeated where the machine
drew fewer than ``fps``). In a window the drummers are drawn straight into the window's
framebuffer (Q/Esc or closing the window quits).

Cost and limits: N renders (and N shadow passes) per frame, so the frame rate falls with N
and the frame size (``livedrummer bench stage`` measures it); a recording is drawn live,
not deferred as the single-drummer display's is, and has no drum track; the stage camera is
fixed (no camera keys); the synths' expression presets are not applied live.
"""

from __future__ import annotations

import json
import logging
import math
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np
import zmq

from livedrummer.avatar.model import Avatar
from livedrummer.kit.lights import LightRig
from livedrummer.kit.model import Kit
from livedrummer.live.ahead import RenderAhead
from livedrummer.render.body_scene import frame_from_pose
from livedrummer.stage.formation import Placement

from ..process.service import OnReady, Service
from ..wire.net import Security
from .live import FrameClock
from .pose_stream import PoseStream
from .stage_export import StagePainter
from .video import VideoSettings, VideoWriter
from .window import WindowOptions

log = logging.getLogger("livedrummer.display")
GLOW_LIT = 0.1  # a piece glowing above this was struck within about 0.3 s (a contact)


@dataclass(frozen=True)
class StagePerformer:
    """One live drummer of the stage: its stream, its performer id, its kit and its spot."""

    label: str
    performer: int
    sub: str
    kit: Kit
    placement: Placement
    avatar: Avatar | None = None


@dataclass
class StageConfig:
    fps: float = 30.0
    size: tuple[int, int] = (640, 360)
    camera: str = "stage"
    frames: int | None = None  # stop after this many frames
    seconds: float | None = None  # stop this long after the first frame with a pose
    out: Path | None = None  # frames.jsonl (and PNGs) folder
    png: bool = True
    video: Path | None = None
    window: WindowOptions | None = None
    render: bool = True
    display_offset_s: float = 0.0
    security: Security = field(default_factory=Security)
    control: str | None = None
    lights: LightRig | None = None  # the show lights (None: the default look)


class _Stream(PoseStream):
    """One performer's pose stream: its :class:`PoseStream` and who it is."""

    def __init__(self, who: StagePerformer) -> None:
        super().__init__(who.kit, f"display pose stream of {who.label}", log, who.performer)
        self.who = who


class _Recorder:
    """Merged frames into a video on show time: a frame that comes late repeats the last."""

    def __init__(self, path: Path, settings: VideoSettings) -> None:
        self._writer = VideoWriter(path, settings)
        self._fps = settings.fps
        self._show0: float | None = None
        self._last: np.ndarray | None = None
        self.frames = 0
        self.repeated = 0

    def add(self, rgba: np.ndarray, show_s: float) -> None:
        if self._show0 is None:
            self._show0 = show_s
        index = round((show_s - self._show0) * self._fps)
        if index < self.frames:
            return
        while self.frames < index and self._last is not None:
            self._writer.write(self._last)
            self.frames += 1
            self.repeated += 1
        self._writer.write(rgba)
        self._last = rgba
        self.frames += 1

    def close(self) -> None:
        self._writer.close()


class _Window:
    """A window the stage is drawn straight into (its default framebuffer)."""

    def __init__(self, options: WindowOptions) -> None:
        from contextlib import ExitStack

        from .window import open_window

        self._stack = ExitStack()
        self.glfw, self.window, self.ctx = self._stack.enter_context(open_window(options))
        w, h = self.glfw.get_framebuffer_size(self.window)
        self.size = (int(w), int(h))

    def present(self) -> bool:
        self.glfw.swap_buffers(self.window)
        self.glfw.poll_events()
        for key in (self.glfw.KEY_Q, self.glfw.KEY_ESCAPE):
            if self.glfw.get_key(self.window, key) == self.glfw.PRESS:
                self.glfw.set_window_should_close(self.window, True)
        return not self.glfw.window_should_close(self.window)

    def close(self) -> None:
        self._stack.close()


class StageDisplay(Service):
    """See the module docstring."""

    name = "display"

    def __init__(
        self,
        performers: list[StagePerformer],
        config: StageConfig,
        clock: FrameClock,
        ctx: zmq.Context[zmq.Socket[bytes]],
    ) -> None:
        super().__init__(clock, ctx, security=config.security, control=config.control, log=log)
        if not performers:
            raise ValueError("a stage display needs at least one performer")
        self.clock: FrameClock = clock
        self.config = config
        self.streams = [_Stream(p) for p in performers]
        self.frames = 0
        self.drawn_s: list[float] = []  # wall time each frame took to draw (bench stage)

    def open(self) -> None:
        for k, s in enumerate(self.streams):
            s.connect(self.ctx, s.who.sub, f"sub endpoint of {s.who.label}", self.config.security)
            self.endpoints[f"sub{k}"] = s.who.sub

    def release(self) -> None:
        for s in self.streams:
            s.close()

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        cfg = self.config
        window: _Window | None = None
        gl: Any = None
        painter: StagePainter | None = None
        recorder: _Recorder | None = None
        log_file: IO[str] | None = None
        poller = zmq.Poller()
        for s in self.streams:
            poller.register(s.rx.sock, zmq.POLLIN)
        try:
            performers = [s.who for s in self.streams]
            if cfg.window is not None:
                window = _Window(cfg.window)
                painter = StagePainter(
                    window.ctx,
                    performers,
                    window.size,
                    cfg.camera,
                    target=window.ctx.screen,
                    lights=cfg.lights,
                )
            elif cfg.render:
                from .context import headless_context

                gl = headless_context()
                painter = StagePainter(gl, performers, cfg.size, cfg.camera, lights=cfg.lights)
            if cfg.video is not None and painter is not None and window is None:
                recorder = _Recorder(cfg.video, VideoSettings(size=cfg.size, fps=round(cfg.fps)))
            if cfg.out is not None:
                cfg.out.mkdir(parents=True, exist_ok=True)
                log_file = (cfg.out / "frames.jsonl").open("w", buffering=1)
            period = 1.0 / cfg.fps
            ahead = RenderAhead()
            next_frame = self.clock.now()
            end = math.inf if cfg.seconds is None else self.clock.now() + cfg.seconds
            drawn = False
            while not stop.is_set() and (cfg.frames is None or self.frames < cfg.frames):
                wait_ms = max(0, int((next_frame - self.clock.now()) * 1000))
                if poller.poll(wait_ms):
                    self._drain()
                now = self.clock.now()
                if now >= end:
                    break
                if now < next_frame:
                    continue
                self._drain()
                show = now + self.clock.latency_s() + ahead.seconds + cfg.display_offset_s
                record, scene = self._frame(show)
                record.update(frame=self.frames, render_s=now, show_s=show)
                any_pose = any(p["pose_s"] is not None for p in record["performers"])
                if painter is not None:
                    painter.draw(scene)
                    if window is not None and not window.present():
                        stop.set()
                    keep = recorder is not None and (any_pose or recorder.frames > 0)
                    png = cfg.out is not None and cfg.png and window is None
                    if keep or png:
                        rgba = painter.read_rgba()
                        if recorder is not None and keep:
                            recorder.add(rgba, show)
                        if png and cfg.out is not None:
                            from .png import write_png

                            write_png(cfg.out / f"frame_{self.frames:06d}.png", rgba[::-1, :, :3])
                record["done_s"] = self.clock.now()
                ahead.add(record["done_s"] - now)
                self.drawn_s.append(record["done_s"] - now)
                if log_file is not None:
                    log_file.write(json.dumps(record) + "\n")
                self.frames += 1
                next_frame = max(next_frame + period, now)
                if any_pose and not drawn:
                    drawn = True
                    end = end if cfg.seconds is None else now + cfg.seconds
                    if on_ready is not None:
                        on_ready()
                        on_ready = None
        finally:
            if log_file is not None:
                log_file.close()
            if recorder is not None:
                recorder.close()
            if window is not None:
                window.close()
            if gl is not None:
                gl.release()
            self.shutdown()
        return 0

    def _drain(self) -> None:
        for s in self.streams:
            s.drain()  # the forwarded onsets, controls and cues: the stage sounds none

    def _frame(self, show: float) -> tuple[dict[str, Any], list[Any]]:
        """Each performer's pose at ``show``: the frames.jsonl record and the scene frames."""
        entries: list[dict[str, Any]] = []
        scene: list[Any] = []
        for s in self.streams:
            got = s.track.at(show)
            entry: dict[str, Any] = {"id": s.who.label, "performer": s.who.performer,
                                     "pose_s": None, "newest_s": s.track.newest_s,
                                     "lit": []}  # fmt: skip
            frame = None
            if got is not None:
                pose_s, row = got
                entry["pose_s"] = pose_s
                lit = np.flatnonzero(np.asarray(row["glow"]) > GLOW_LIT)
                entry["lit"] = [s.who.kit.pieces[int(i)].name for i in lit]
                s.stats.lit_frames += int(lit.size > 0)
                frame = frame_from_pose(row, show, s.who.kit)
            entries.append(entry)
            scene.append(frame)
        return {"performers": entries}, scene

    def summary(self) -> dict[str, Any]:
        each = {s.who.label: dict(s.stats.__dict__) for s in self.streams}
        return {"frames": self.frames, "performers": each}
