"""Recording a live display: frames on show time into a video, the drum track muxed in later.

A live display renders frames when its clock says so, and on a busy machine it may skip
some. A recording is a constant-frame-rate video, so :class:`LiveRecorder` places each
rendered frame at its index on the video's own grid, ``round((show - show0) * fps)``: a frame
that fell behind the grid repeats the previous image (counted as ``repeated``), one that lands
on an index already written is left out (``skipped``). The picture therefore keeps the show's
time, and a sound placed at ``t - show0`` lines up with what was shown at ``t``.

The live display hears no sound (it subscribes to poses), so the recording is written as video
only; its timing goes into a sidecar ``<file>.timing.json`` (``show0_s``, ``fps``,
``frames``), and whoever knows the onsets (``livedrummer up --video`` reads them back from the
session journal) makes the track with :func:`recording_track` (onsets at onset + D on the
video's time, cymbal chokes from the journaled controls stopping the sound as they stop the
cymbal, and the hi-hat pedal closing the ringing hi-hat, as the live sound does; the built-in
kit or a SoundFont) and calls :func:`mux_audio`, which copies the video
packets into a new file beside an AAC track (no re-encoding of the picture).

Memory stays bounded however long the show: the recorder keeps one image (the last, for
repeats) and the video is fragmented MP4 (:mod:`~services.display.video`), whose muxer keeps no
per-frame index.

Limits: the sidecar is written when the recorder closes (a killed display leaves a playable
video, since the writer closes in a ``finally`` and a fragmented file plays up to its last
fragment even after SIGKILL, but no sidecar if it dies with SIGKILL).
"""

from __future__ import annotations

import json
import logging
import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import NoteMap

from .context import DisplayError
from .renderer import Renderer, i420_ok
from .video import VideoSettings, VideoWriter, encode_audio

log = logging.getLogger(__name__)


def timing_path(video: Path) -> Path:
    return video.with_name(video.name + ".timing.json")


@dataclass(frozen=True)
class Timing:
    show0_s: float  # show time (shared clock) of the video's first frame
    fps: int
    frames: int

    @classmethod
    def load(cls, video: Path) -> Timing:
        path = timing_path(video)
        try:
            data = json.loads(path.read_text())
            return cls(float(data["show0_s"]), int(data["fps"]), int(data["frames"]))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise DisplayError(f"{path}: no recording timing ({exc})") from None


class LiveRecorder:
    """See the module docstring."""

    def __init__(self, path: Path, settings: VideoSettings) -> None:
        self.path = Path(path)
        self.settings = settings
        self._writer = VideoWriter(self.path, replace(settings, fragmented=True))
        self._yuv = i420_ok(settings.size)
        self._show0: float | None = None
        self._last: np.ndarray | None = None
        self.frames = 0
        self.repeated = 0
        self.skipped = 0

    def add(self, renderer: Renderer, show_s: float) -> None:
        """The frame the renderer just drew, meant to be seen at ``show_s``."""
        if self._show0 is None:
            self._show0 = show_s
        index = round((show_s - self._show0) * self.settings.fps)
        if index < self.frames:
            self.skipped += 1
            return
        while self.frames < index and self._last is not None:
            self._writer.write(self._last)
            self.frames += 1
            self.repeated += 1
        image = renderer.read_i420() if self._yuv else renderer.read_rgba()
        self._writer.write(image)
        self._last = image
        self.frames += 1

    def close(self) -> Timing | None:
        self._writer.close()
        if self._show0 is None:
            return None
        timing = Timing(self._show0, self.settings.fps, self.frames)
        timing_path(self.path).write_text(json.dumps(timing.__dict__) + "\n")
        log.info(
            "recorded %d frames to %s (%d repeated, %d skipped)",
            self.frames,
            self.path,
            self.repeated,
            self.skipped,
        )
        return timing


def recording_track(
    onsets: np.ndarray,
    controls: np.ndarray,
    timing: Timing,
    *,
    delay_s: float,
    kit: Kit,
    note_map: NoteMap,
    soundfont: Path | None = None,
    sample_rate: int = 48_000,
) -> np.ndarray:
    """The drum track of a recording, (frames / fps * sample_rate, 2) float32: ``onsets`` and
    ``controls`` (stamped on the shared clock) sounded at ``time + delay_s`` on the video's
    time, each grab in ``controls`` stopping its cymbal (the notes read through ``note_map``
    onto ``kit``'s pieces, as the body does) and each closing of the hi-hat pedal its ringing
    hi-hat (:func:`~livedrummer.audio.cuts.sound_chokes`, as the live sound cuts them), with
    ``soundfont``'s kit when given.

    The track is mixed into :func:`spooled_track`, not into the process's memory: a show's
    track is 1.4 GB an hour."""
    from livedrummer.audio.cuts import sound_chokes
    from livedrummer.audio.mix import mix_onsets

    shift = delay_s - timing.show0_s
    on = np.sort(onsets, order="time_s")
    on["time_s"] += shift
    ctl = np.sort(controls, order="time_s")
    ctl["time_s"] += shift
    chokes = sound_chokes(ctl, note_map, kit)  # grabs, and the pedal closing the hi-hat
    duration = timing.frames / timing.fps
    out = spooled_track(round(duration * sample_rate))
    if soundfont is not None:
        from livedrummer.audio.kitfile import render_kit_file

        return render_kit_file(on, duration, soundfont, sample_rate, kit, chokes, out)
    return mix_onsets(on, duration, kit, sample_rate, chokes, out)


def spooled_track(samples: int) -> np.ndarray:
    """Zeros, (samples, 2) float32, in an unlinked temporary file mapped into memory: its pages
    are the kernel's page cache, written out to disk under memory pressure, not memory the
    process holds; the file's space is freed with the array."""
    if samples == 0:
        return np.zeros((0, 2), np.float32)
    with tempfile.TemporaryFile(prefix="livedrummer-track-") as f:
        return np.memmap(f, np.float32, "w+", shape=(samples, 2))  # the map outlives the fd


def mux_audio(video: Path, stereo: np.ndarray, sample_rate: int = 48_000) -> None:
    """Add ``stereo`` ((N, 2) float32, starting with the video's first frame) to ``video`` as
    an AAC track, copying its video packets; replaces the file."""
    import av

    tmp = video.with_name(video.name + ".mux" + video.suffix)
    try:
        with av.open(str(video)) as src, av.open(str(tmp), mode="w") as dst:
            vin = src.streams.video[0]
            vout: Any = dst.add_stream_from_template(vin)
            aout: Any = dst.add_stream("aac", rate=sample_rate)
            aout.layout = "stereo"
            encode_audio(dst, aout, stereo, sample_rate)
            for packet in src.demux(vin):
                if packet.dts is None:  # the demuxer's flush packet
                    continue
                packet.stream = vout
                dst.mux(packet)
        os.replace(tmp, video)
    except (OSError, ValueError) as exc:  # PyAV's errors are OSError subclasses
        tmp.unlink(missing_ok=True)
        raise DisplayError(f"cannot add the drum track to {video}: {exc}") from None
