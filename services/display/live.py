"""Live display: subscribe to a synth's poses and render each frame for the time it is seen.

Why a frame clock. A pose sample is stamped with its *show time* on the shared clock; a frame
rendered now appears some milliseconds later (the swap, the projector). The display asks a
:class:`FrameClock` for the show time of the frame it is about to render and draws the pose
track at that time. Production uses :class:`AudioFrameClock`: the sounddevice output stream's
time plus its reported output latency (the picture follows what the audience hears), mapped
onto the shared clock; headless runs and CI use :class:`MonotonicFrameClock`. The display's
own latency, from starting a frame to its being done (written, or presented), is measured
on the frames just drawn (:class:`~livedrummer.live.ahead.RenderAhead`) and added too, so a
contact is drawn in the frame that is seen at its show time, not one render later
(``render_ahead=False`` leaves it out). Calibration offsets (``calibration.toml``) are
added: audio to the audio clock, display to every frame.

Loop. One thread: drain the SUB socket (POSE messages into a
:class:`~livedrummer.live.track.PoseTrack`), wait for the next frame time, render the track at
the frame's show time (holding the last pose when the stream stops, resuming when it comes
back), hand the image to a sink (PNG files, a window). ``frames.jsonl`` records, per frame,
its render time, its show time, the show time of the pose drawn and of the newest pose
received by then, so a test or a bench can check contacts and latency without pixels.

Bad input. The stream is read by a :class:`~services.display.pose_stream.PoseStream` (the
stage display's too), on the one :class:`~services.wire.stream_rx.StreamReceiver`: the SUB socket
takes every message that starts with the protocol magic (so a synth of another protocol
version is seen and counted, not filtered into silence); a message that fails to decode, or a
valid one that is not a POSE (or a SHOWN_ONSET or SHOWN_CONTROL, the onsets and controls the
synth forwards: counted, sequence-checked and left to the sound process, which subscribes to
them on its own socket, :mod:`~services.display.live_sound`), is dropped and counted per kind
in ``bad`` (:class:`~services.wire.badmsg.BadMessages`, logged once per kind, totals logged when
the loop ends and in ``summary()``), and the next one is read. Sequence numbers follow the
one policy of :mod:`livedrummer.protocol.sequence`: a gap is counted in ``missing``, a
restarted synth is taken, a duplicate is dropped.

Limits: the pose format is taken from the kit given to the display (the synth's READY also
carries it; a mismatch is refused by hash, frame by frame); one performer. Frames go to a
:mod:`~services.display.surface`: a window (``config.window``; the stage) or off screen, where
they can also be written as PNGs (``--frames-dir``) and recorded into a video on show time,
from the first frame that draws the drummer
(``config.video``, :mod:`~services.display.record`). A remote display sets
``config.security`` (our key pair and the synth's public key) to subscribe over CURVE.

A set-length headless recording (``config.video`` with ``config.seconds``: ``up --video
--seconds``, the demo) is not drawn during the show: every pose message is spooled to a
temporary file with its arrival time, and each frame's render and show times are kept; after
the show the frames are drawn from the spool exactly as an infinitely fast display would have
drawn them, so the video has every frame even where the machine could not draw 30 a second
live (on 2 cores with llvmpipe a 720p frame of the character takes 60-120 ms), and the live
run does not compete with the synth for the CPU. Where even the loop without drawing missed
ticks (a machine loaded by other work), the missed frames are scheduled too, ``1/fps`` apart
(:func:`missed_ticks`), each drawn from what had arrived by its own render time. It costs the
drawing time after the show (about 90 s for the 30 s demo here). Open-ended recordings are
still drawn live.

Show control. With ``config.osc_port`` or ``config.cues``, OSC camera, blackout and cue
commands, and the synth's STAGE_CUE messages (a bar cue's camera and blackout, at its show
time), are applied before each frame (:mod:`services.display.showctl`); frames.jsonl then also
names each frame's camera and darkness (unrounded, 0..1; and ``cues``: the stage cues applied
in it, with their show times and whether they arrived late), and a recording drawn after the
show replays them.

Strips. ``config.overlays`` (``display --live --overlay score,joints``; keys O and G in a
window) draws SMED's score and joint-angle strips over each frame at its show time, from the
forwarded onsets and the poses received (:class:`~livedrummer.render.live_overlay.LiveStrips`);
a deferred recording keeps the onsets with their arrival times and replays both into fresh
strips, so each frame shows what had arrived by its render time.

Life cycle: the service base's (:mod:`services.process.service`); readiness comes after the first
frame that drew the drummer, and a control socket answering HELLO with READY (service
"display", role "frames", the pose format) is bound only when ``config.control`` names one,
since ``up`` may run several displays.
"""

from __future__ import annotations

import json
import logging
import math
import struct
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, Any, Protocol

import numpy as np
import zmq

from livedrummer.avatar.model import Avatar
from livedrummer.body.pose import pose_dtype
from livedrummer.body.skeleton import J
from livedrummer.kit.lights import LightRig
from livedrummer.kit.model import Kit
from livedrummer.live.ahead import RenderAhead
from livedrummer.live.behind import BehindCounter
from livedrummer.live.track import PoseTrack
from livedrummer.protocol import Hello, Kind
from livedrummer.render.background import Background
from livedrummer.render.body_scene import frame_from_pose
from livedrummer.render.live_overlay import LiveStrips

from ..process.service import OnReady, Service
from ..wire.net import Security
from .pose_stream import PoseStream
from .record import LiveRecorder
from .showctl import DisplayShow, replay_stage
from .surface import HeadlessSurface, WindowSurface
from .video import VideoSettings
from .window import WindowOptions

log = logging.getLogger("livedrummer.display")
#: One pose message in a deferred recording's spool: arrival time (s), sample count.
SPOOL_HEAD = struct.Struct("<dI")
#: A window says the stream stalled once its newest pose is this old (the live readout).
STALLED_S = 0.5

DEFAULT_SUB = "tcp://127.0.0.1:5720"


class FrameClock(Protocol):
    def now(self) -> float:
        """Shared-clock time now (seconds)."""
        ...

    def latency_s(self) -> float:
        """How long after ``now`` a frame rendered now is seen."""
        ...


class FrameExtra(Protocol):
    """Drawn over each frame after the player (the practice rig's teacher and readout,
    :mod:`services.display.practice_view`); not in a deferred recording."""

    def draw(self, surface: Any, show_s: float) -> None: ...

    def record(self) -> dict[str, Any]:
        """What to add to the frame's line in frames.jsonl."""
        ...

    def close(self) -> None: ...


class MonotonicFrameClock:
    """The shared monotonic clock with a fixed latency (headless, CI)."""

    def __init__(self, latency_s: float = 0.0) -> None:
        self._latency = latency_s

    def now(self) -> float:
        return time.monotonic_ns() * 1e-9

    def latency_s(self) -> float:
        return self._latency


class AudioFrameClock:
    """The audio output stream's clock, mapped onto the shared clock, plus its output
    latency. Needs sounddevice and PortAudio (libportaudio2); raises DisplayError without."""

    def __init__(self, extra_latency_s: float = 0.0, sample_rate: int = 48_000) -> None:
        from .context import DisplayError

        try:
            import sounddevice as sd
        except OSError as exc:
            raise DisplayError(f"no audio clock: {exc} (install libportaudio2)") from None
        try:
            self._stream = sd.OutputStream(samplerate=sample_rate, channels=1, dtype="float32")
            self._stream.start()
        except sd.PortAudioError as exc:
            raise DisplayError(f"no audio clock: cannot open an output stream: {exc}") from None
        out_latency = self._stream.latency
        self._latency = float(out_latency) + extra_latency_s
        self._offset = time.monotonic_ns() * 1e-9 - float(self._stream.time)

    def now(self) -> float:
        return float(self._stream.time) + self._offset

    def latency_s(self) -> float:
        return self._latency

    def close(self) -> None:
        self._stream.stop()
        self._stream.close()


@dataclass
class LiveConfig:
    sub: str = DEFAULT_SUB
    fps: float = 60.0
    frames: int | None = None  # stop after this many frames (headless runs)
    # stop this long after the first frame that drew a pose (or after this long with none)
    seconds: float | None = None
    out: Path | None = None  # PNG folder (and frames.jsonl)
    size: tuple[int, int] = (640, 360)
    camera: str = "stage"
    display_offset_s: float = 0.0
    render: bool = True
    window: WindowOptions | None = None  # a window instead of off-screen rendering
    video: Path | None = None  # record the frames (headless) into this video file
    png: bool = True  # with ``out``: write each frame as a PNG (frames.jsonl is always written)
    render_ahead: bool = True  # draw each frame for when it is done, not when it is begun
    security: Security = field(default_factory=Security)
    control: str | None = None  # HELLO/READY endpoint (none unless asked: up runs many displays)
    avatar: Avatar | None = None  # who is drawn (None: the built-in character); READY says which
    background: Background | None = None  # behind the stage, off screen (None: the hall)
    lights: LightRig | None = None  # the show lights it starts with (None: the default look)
    osc_port: int | None = None  # OSC camera and blackout (services.display.showctl)
    osc_allow: tuple[str, ...] = ()
    cues: dict[str, Any] = field(default_factory=dict)  # livedrummer.live.cues, by name
    overlays: frozenset[str] = frozenset()  # strips drawn from the start: "score", "joints"
    extra: FrameExtra | None = None  # drawn over each frame (the practice rig's view)


@dataclass
class LiveStats:
    pose_messages: int = 0
    pose_samples: int = 0
    missing: int = 0
    bad: int = 0
    frames: int = 0
    shown_onsets: int = 0  # onsets the synth forwarded (SHOWN_ONSET; --sound plays them)
    shown_controls: int = 0  # controls it forwarded (SHOWN_CONTROL; --sound cuts by them)
    held: int = 0  # frames drawn with no pose at or after their show time - 1 frame


def missed_ticks(
    schedule: list[tuple[float, float]], now: float, lead_s: float, period: float
) -> list[tuple[float, float]]:
    """(render_s, show_s) of the frames a loaded machine's loop had no time to tick since the
    last one in ``schedule``: an infinitely fast display would have drawn them, ``period``
    apart, each ``lead_s`` ahead of its render time as this frame is."""
    if not schedule:
        return []
    last = schedule[-1][0]
    count = max(0, round((now - last) / period) - 1)
    return [(last + k * period, last + k * period + lead_s) for k in range(1, count + 1)]


def draw_strips(
    surface: HeadlessSurface | WindowSurface, strips: LiveStrips, show_s: float
) -> None:
    """Blend the strips the surface shows, at the frame's show time, over the frame drawn."""
    if surface.overlays:
        image = strips.image(surface.renderer.size, surface.overlays)
        r = image.rect
        if not image.empty:
            surface.overlay(image.paint(show_s), (r.x, r.y, r.width, r.height))


class LiveDisplay(Service):
    """See the module docstring."""

    name = "display"

    def __init__(
        self,
        kit: Kit,
        config: LiveConfig,
        clock: FrameClock,
        ctx: zmq.Context[zmq.Socket[bytes]],
    ) -> None:
        super().__init__(clock, ctx, security=config.security, control=config.control, log=log)
        self.clock: FrameClock = clock
        self.kit = kit
        self.config = config
        self.stream = PoseStream(kit, "display pose stream", log)
        self.format = self.stream.format
        self.stats = LiveStats()
        self.bad = self.stream.bad
        self._last_show = -math.inf  # show time of the last frame drawn
        self._spool: IO[bytes] | None = None  # pose messages of a deferred recording
        self.late = BehindCounter(
            "pose messages arrived after every frame they cover",
            "measured on this machine: the synth's answer took longer "
            "than the show delay (--delay-ms), so those frames drew the "
            "drummer from the pose before",
        )
        self.held = BehindCounter("frames drawn with a stale pose (the pose stream stalled)")
        self.show: DisplayShow | None = None
        self.strips = LiveStrips(kit)  # fed only where strips may be drawn (see run)
        self._strips_fed = False
        self._onset_log: list[tuple[float, np.ndarray]] = []  # a deferred recording's onsets

    @property
    def track(self) -> PoseTrack:
        """The poses received, at their show times (the stream's)."""
        return self.stream.track

    @track.setter
    def track(self, track: PoseTrack) -> None:
        self.stream.track = track

    def open(self) -> None:
        """Connect to the synth's poses (the base binds the control socket, if one is asked)."""
        self.stream.connect(self.ctx, self.config.sub, "sub endpoint", self.config.security)
        self.endpoints["sub"] = self.config.sub
        port = self.config.osc_port
        if port is not None or self.config.cues:
            self.show = DisplayShow(
                self.kit,
                self.config.camera,
                port,
                self.config.osc_allow,
                self.config.cues,
                self.config.lights,
            )
        if self.show is not None and self.show.osc is not None:
            self.endpoints["osc"] = f"udp://127.0.0.1:{self.show.osc.port}"

    def release(self) -> None:
        if self.show is not None:
            self.show.close()
            self.show = None
        self.stream.close()

    def hello(self) -> Hello:
        avatar = "" if self.config.avatar is None else self.config.avatar.digest
        return Hello(
            self.name, "frames", self.performer, dict(self.endpoints), self.format, avatar=avatar
        )

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        """Draw until ``stop``; ``on_ready`` is called once, after the first frame that drew
        a pose (the display is "ready" when it shows the drummer, not when it has a socket)."""
        cfg = self.config
        surface: HeadlessSurface | WindowSurface | None = None
        recorder: LiveRecorder | None = None
        log_file: IO[str] | None = None
        try:
            if cfg.window is not None:
                window = (
                    cfg.window if cfg.lights is None else replace(cfg.window, lights=cfg.lights)
                )
                surface = WindowSurface(self.kit, window, cfg.avatar)
            elif cfg.render:
                surface = HeadlessSurface(
                    self.kit, cfg.size, cfg.camera, cfg.avatar, cfg.background, cfg.lights
                )
            if surface is not None and self.show is not None:
                surface.stage = self.show.stage
            if surface is not None and not isinstance(surface, WindowSurface):
                surface.overlays = cfg.overlays
            self._strips_fed = surface is not None and (bool(cfg.overlays) or bool(cfg.window))
            # A set-length headless recording is drawn after the show from what arrived (see
            # the module docstring): every frame at full rate, and no drawing during the show.
            deferred = (
                cfg.video is not None
                and isinstance(surface, HeadlessSurface)
                and cfg.seconds is not None
            )
            schedule: list[tuple[float, float]] = []  # (render_s, show_s) of each frame
            if deferred:
                self._spool = tempfile.TemporaryFile()
            elif cfg.video is not None and isinstance(surface, HeadlessSurface):
                settings = VideoSettings(size=cfg.size, fps=round(cfg.fps))
                recorder = LiveRecorder(cfg.video, settings)
            if cfg.out is not None:
                cfg.out.mkdir(parents=True, exist_ok=True)
                # Line-buffered: a watcher (tests, bench recovery) sees each frame as drawn.
                log_file = (cfg.out / "frames.jsonl").open("w", buffering=1)
            period = 1.0 / cfg.fps
            ahead = RenderAhead()
            next_frame = self.clock.now()
            # --seconds: from the start until the first pose is drawn, then from that frame
            end = math.inf if cfg.seconds is None else self.clock.now() + cfg.seconds
            drawn = False
            # ... measured in show time once the drummer is drawn: a recording spans show time,
            # and render-ahead's lead grows after the first frames, so a wall-clock end would
            # record a frame or two more than asked
            show_end = math.inf
            while not stop.is_set() and (cfg.frames is None or self.stats.frames < cfg.frames):
                wait_ms = max(0, int((next_frame - self.clock.now()) * 1000))
                if self.stream.rx.poll(wait_ms):
                    self._drain()
                now = self.clock.now()
                if now >= end:
                    break
                if now < next_frame:
                    continue
                self._drain()
                lead = ahead.seconds if cfg.render_ahead else 0.0
                show = now + self.clock.latency_s() + lead + cfg.display_offset_s
                if show >= show_end:
                    break
                got = self.track.at(show)
                record: dict[str, Any] = {"frame": self.stats.frames, "render_s": now,
                                          "show_s": show, "pose_s": None,
                                          "newest_s": self.track.newest_s}  # fmt: skip
                if self.show is not None:  # OSC commands reach this very frame
                    if fired := self.show.apply(now, show):  # and stage cues due by its show
                        record["cues"] = fired
                    record["camera"] = self.show.stage.camera
                    # unrounded: the first frame of a fade is dark by as little as 1e-6
                    record["dark"] = self.show.stage.darkness(now)
                    record["look"] = self.show.stage.lights_at(now).name
                if got is not None:
                    pose_s, row = got
                    record["pose_s"] = pose_s
                    # the sample after the drawn one: later than the show time unless the
                    # frame skipped one that was due (a test's check, and a lag figure's)
                    record["next_s"] = self.track.next_after(pose_s)
                    record["tips"] = (
                        np.asarray(row["position"])[[J["r_tip"], J["l_tip"]]].round(5).tolist()
                    )
                    if show - pose_s > period:
                        self.stats.held += 1
                        self._say(self.held.add(1, now))
                    if isinstance(surface, WindowSurface):
                        stalled = show - pose_s > STALLED_S
                        surface.state = "stream stalled: last pose held" if stalled else "playing"
                    if surface is not None and not deferred:
                        surface.draw(frame_from_pose(row, show, self.kit), now)
                elif surface is not None and not deferred:
                    if isinstance(surface, WindowSurface):
                        surface.state = (
                            "no poses: is the synth running?" if drawn else ("waiting for poses")
                        )
                    surface.draw(None, now)
                if surface is not None and not deferred:
                    draw_strips(surface, self.strips, show)
                    if cfg.extra is not None:
                        cfg.extra.draw(surface, show)
                        record.update(cfg.extra.record())
                if (
                    recorder is not None
                    and surface is not None
                    and (got is not None or recorder.frames)
                ):
                    recorder.add(surface.renderer, show)  # from the first frame with a pose
                if deferred and (got is not None or schedule):
                    schedule.extend(missed_ticks(schedule, now, show - now, period))
                    schedule.append((now, show))
                if (
                    isinstance(surface, HeadlessSurface)
                    and cfg.out is not None
                    and cfg.png
                    and not deferred
                ):
                    from .png import write_png

                    write_png(
                        cfg.out / f"frame_{self.stats.frames:06d}.png", surface.renderer.read_rgb()
                    )
                if surface is not None and not surface.present():
                    stop.set()  # the window was closed
                record["done_s"] = self.clock.now()
                ahead.add(record["done_s"] - now)
                if log_file is not None:
                    log_file.write(json.dumps(record) + "\n")
                self.stats.frames += 1
                next_frame = max(next_frame + period, now)
                self._last_show = show
                self._say(self.late.poll(now))
                if got is not None and not drawn:
                    drawn = True
                    end = end if cfg.seconds is None else now + cfg.seconds + 1.0  # a backstop
                    show_end = show_end if cfg.seconds is None else show + cfg.seconds
                if on_ready is not None and got is not None:
                    on_ready()
                    on_ready = None
            if deferred and isinstance(surface, HeadlessSurface):
                recorder = self._replay(surface, schedule)
        finally:
            if self._spool is not None:
                self._spool.close()
                self._spool = None
            if log_file is not None:
                log_file.close()
            if recorder is not None:
                recorder.close()
                if recorder.frames and recorder.repeated > 0.05 * recorder.frames:
                    log.warning(
                        "display: the recording repeats %d of its %d frames (%.0f %%): "
                        "this machine drew fewer frames than --fps asked",
                        recorder.repeated,
                        recorder.frames,
                        100 * recorder.repeated / recorder.frames,
                    )
            if cfg.extra is not None:
                cfg.extra.close()
            if surface is not None:
                surface.close()
            self.shutdown()
        return 0

    def _replay(
        self, surface: HeadlessSurface, schedule: list[tuple[float, float]]
    ) -> LiveRecorder:
        """Draw the recording of a show from its spool: each frame of ``schedule`` from the
        pose messages that had arrived by its render time, as the loop would have drawn it."""
        cfg = self.config
        spool, video = self._spool, cfg.video
        if spool is None or video is None:
            raise RuntimeError("_replay needs the spool of a --video recording")
        recorder = LiveRecorder(video, VideoSettings(size=cfg.size, fps=round(cfg.fps)))
        track = PoseTrack()
        dtype = pose_dtype(len(self.kit.pieces))
        spool.seek(0)

        def messages() -> Iterator[tuple[float, np.ndarray, np.ndarray]]:
            while head := spool.read(SPOOL_HEAD.size):
                arrival, n = SPOOL_HEAD.unpack(head)
                show = np.frombuffer(spool.read(8 * n), np.float64)
                rows = np.frombuffer(spool.read(n * dtype.itemsize), dtype)
                yield arrival, show, rows

        pending = messages()
        nxt = next(pending, None)
        strips = LiveStrips(self.kit)
        onsets = iter(self._onset_log)
        nxt_onsets = next(onsets, None)
        stage = None if self.show is None else replay_stage(self.kit, self.show)
        surface.stage = None if stage is None else stage.stage
        started = time.monotonic()
        print(
            f"display: drawing the recording, {len(schedule)} frames at {cfg.fps:g} fps "
            f"({cfg.size[0]}x{cfg.size[1]}) ...",
            file=sys.stderr,
            flush=True,
        )
        try:
            for render_s, show_s in schedule:
                while nxt is not None and nxt[0] <= render_s:
                    track.add(nxt[1], nxt[2])
                    if surface.overlays:
                        strips.add_poses(nxt[1], nxt[2]["position"])
                    nxt = next(pending, None)
                while nxt_onsets is not None and nxt_onsets[0] <= render_s:
                    strips.add_onsets(nxt_onsets[1])
                    nxt_onsets = next(onsets, None)
                got = track.at(show_s)
                if stage is not None:
                    stage.at(render_s)  # the camera and blackout as they were at this frame
                frame = None if got is None else frame_from_pose(got[1], show_s, self.kit)
                surface.draw(frame, render_s)
                draw_strips(surface, strips, show_s)
                recorder.add(surface.renderer, show_s)
        except BaseException:
            recorder.close()
            raise
        print(
            f"display: recording drawn in {time.monotonic() - started:.1f} s",
            file=sys.stderr,
            flush=True,
        )
        return recorder

    def _drain(self) -> None:
        """Everything waiting on the pose stream (:class:`~.pose_stream.PoseStream`): poses
        into the track, and the onsets, controls and stage cues the synth forwards."""
        batch = self.stream.drain()
        for msg in batch.forwarded:
            if msg.kind is Kind.STAGE_CUE:  # a bar cue's camera and blackout (showctl)
                if self.show is None:
                    self.stream.unexpected("STAGE_CUE (no stage here: give --cues or --osc)")
                else:
                    self.show.schedule(msg.rows)
            elif msg.kind is Kind.SHOWN_ONSET:  # onsets the synth forwards (sounded apart)
                self.stats.shown_onsets += msg.rows.size
                if self._spool is not None and self.config.overlays:
                    self._onset_log.append((self.clock.now(), msg.rows.copy()))
                elif self._strips_fed:
                    self.strips.add_onsets(msg.rows)
            elif msg.kind is Kind.SHOWN_CONTROL:  # grabs and the pedal (sounded apart)
                self.stats.shown_controls += msg.rows.size
        for show, rows in batch.poses:
            # a message whose every sample is for a frame already drawn came too late to be
            # seen (re-animations also resend recent past samples; those are not counted)
            late = int(show.size > 0 and float(show.max()) < self._last_show)
            self._say(self.late.first(late, self.clock.now()))
            if self._strips_fed and self._spool is None:
                self.strips.add_poses(show, rows["position"])
            if self._spool is not None:
                self._spool.write(SPOOL_HEAD.pack(self.clock.now(), rows.size))
                self._spool.write(np.ascontiguousarray(show, np.float64).tobytes())
                self._spool.write(np.ascontiguousarray(rows).tobytes())
        got = self.stream.stats
        self.stats.pose_messages, self.stats.pose_samples = got.pose_messages, got.pose_samples
        self.stats.missing, self.stats.bad = got.missing, got.bad

    def _say(self, line: str | None) -> None:
        if line is not None:
            log.warning("display: %s", line)

    def summary(self) -> dict[str, Any]:
        s = self.stats
        return {"frames": s.frames, "pose_messages": s.pose_messages,
                "pose_samples": s.pose_samples, "missing": s.missing, "bad": s.bad,
                "held": s.held, "late_samples": self.late.total,
                "bad_messages": self.bad.summary()}  # fmt: skip
