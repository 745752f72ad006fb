"""Video files through PyAV (FFmpeg bundled in its wheels): H.264 + AAC in MP4.

Why PyAV and not a pipe to an ``ffmpeg`` binary: the wheels carry FFmpeg with libx264 and the
AAC encoder, so a clean clone needs no system FFmpeg, and frames go in as numpy arrays without
a subprocess. The audio track is encoded first, whole (the muxer interleaves it with video by
timestamp); video frames are encoded on a worker thread (:class:`VideoWriter`), so the next
frame renders while this one encodes. Frames come as I420 (planar YUV 4:2:0, BT.709, limited
range) already converted on the GPU (:meth:`Renderer.read_i420`), so this thread only copies
the planes into FFmpeg's and runs x264; bottom-up RGBA is still accepted and converted here with
swscale to the same colours. The stream's colour metadata says BT.709 limited range either way.

A recording of unknown length (the live display's) is written as fragmented MP4
(``VideoSettings.fragmented``): the muxer writes each keyframe's group of frames out as a
fragment and keeps no per-frame index in memory, where a plain MP4 holds its whole index until
it closes (measured: 69 bytes a frame, 7 MB an hour at 30 fps), and a writer killed mid-show
leaves a file that plays up to its last fragment.

Video with alpha (``VideoSettings.alpha``, a transparent background for stage video systems to
composite): ``.mov`` is ProRes 4444 (``prores_ks``, 10-bit 4:4:4 with a 10-bit alpha plane;
AAC sound) and ``.webm`` is VP9 with alpha (``libvpx-vp9``, 4:2:0 with an alpha plane; Opus
sound). Both encoders are in PyAV's FFmpeg; frames go in as RGBA and are converted here.
FFmpeg's own VP9 decoder drops the alpha plane: read such a file back with ``libvpx-vp9``.
Without alpha, ``.webm`` is VP9 too and the rest are H.264.

Limits: even width and height (4:2:0 chroma); constant frame rate; one stereo audio track;
AAC pads its last frame, so a decoder may return up to 1024 samples (21 ms) more than was
written.
"""

from __future__ import annotations

import queue
import threading
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .context import DisplayError

AUDIO_FRAME = 1024  # samples per AAC frame
CONTAINERS = (".mp4", ".m4v", ".mov", ".mkv", ".webm")
ALPHA_CONTAINERS = (".mov", ".webm")
BT709 = 1  # FFmpeg's AVCOL_SPC / AVCOL_PRI / AVCOL_TRC code for BT.709
LIMITED_RANGE = 1  # AVCOL_RANGE_MPEG: luma 16..235, chroma 16..240


@dataclass(frozen=True)
class VideoSettings:
    size: tuple[int, int] = (1280, 720)
    fps: int = 60
    crf: int = 20
    preset: str = "veryfast"
    sample_rate: int = 48_000
    fragmented: bool = False  # fragmented MP4: no in-memory index (see the module docstring)
    alpha: bool = False  # keep the frame's alpha: .mov ProRes 4444 or .webm VP9


@dataclass(frozen=True)
class Codec:
    """The video and audio encoders a file gets, by its type and whether it keeps alpha."""

    video: str
    pix_fmt: str
    options: dict[str, str]
    audio: str

    @property
    def alpha(self) -> bool:
        return self.pix_fmt.startswith("yuva")


def codec_for(suffix: str, settings: VideoSettings) -> Codec:
    """The encoders for a file of type ``suffix`` (see the module docstring)."""
    if suffix == ".webm":
        fmt = "yuva420p" if settings.alpha else "yuv420p"
        vp9 = {
            "crf": str(settings.crf + 11),
            "b": "0",
            "deadline": "realtime",
            "cpu-used": "8",
            "row-mt": "1",
        }
        return Codec("libvpx-vp9", fmt, vp9, "libopus")
    if settings.alpha:  # .mov
        return Codec("prores_ks", "yuva444p10le", {"profile": "4", "vendor": "apl0"}, "aac")
    x264 = {
        "crf": str(settings.crf),
        "preset": settings.preset,
        "x264-params": "colorprim=bt709:transfer=bt709:colormatrix=bt709:range=tv",
    }
    return Codec("libx264", "yuv420p", x264, "aac")


def encode_audio(container: Any, stream: Any, stereo: np.ndarray, sample_rate: int) -> None:
    """Encode a whole (N, 2) float track into ``stream`` of ``container`` and mux it, one AAC
    frame at a time (no planar copy of the whole track: it may be an hour on disk)."""
    import av

    for start in range(0, len(stereo), AUDIO_FRAME):
        chunk = np.ascontiguousarray(np.asarray(stereo[start : start + AUDIO_FRAME], np.float32).T)
        frame = av.AudioFrame.from_ndarray(chunk, format="fltp", layout="stereo")
        frame.sample_rate = sample_rate
        frame.pts = start
        frame.time_base = Fraction(1, sample_rate)
        for packet in stream.encode(frame):
            container.mux(packet)
    for packet in stream.encode(None):
        container.mux(packet)


class _Encoder:
    """The PyAV side: an open file with one video and one audio stream (:func:`codec_for`)."""

    def __init__(self, path: str, settings: VideoSettings) -> None:
        import av

        w, h = settings.size
        self.settings = settings
        frag = {"movflags": "frag_keyframe+empty_moov+default_base_moof"}
        self.container: Any = av.open(
            path, mode="w", container_options=frag if settings.fragmented else {}
        )
        self.codec = codec_for(Path(path).suffix.lower(), settings)
        stream: Any = self.container.add_stream(self.codec.video, rate=settings.fps)
        stream.width, stream.height, stream.pix_fmt = w, h, self.codec.pix_fmt
        stream.options = self.codec.options
        self.video = stream
        audio: Any = self.container.add_stream(self.codec.audio, rate=settings.sample_rate)
        audio.layout = "stereo"
        self.audio = audio

    def write_audio(self, stereo: np.ndarray) -> None:
        encode_audio(self.container, self.audio, stereo, self.settings.sample_rate)

    def write(self, image: np.ndarray) -> None:
        import av

        if image.ndim == 2:  # I420, top row first
            frame = av.VideoFrame.from_ndarray(image, format="yuv420p")
        else:
            frame = av.VideoFrame.from_ndarray(
                np.ascontiguousarray(image[::-1]), format="rgba"
            ).reformat(format=self.codec.pix_fmt, dst_colorspace="ITU709")
        frame.colorspace = BT709
        frame.color_primaries = BT709
        frame.color_trc = BT709
        frame.color_range = LIMITED_RANGE
        for packet in self.video.encode(frame):
            self.container.mux(packet)

    def close(self) -> None:
        for packet in self.video.encode(None):
            self.container.mux(packet)
        self.container.close()


def check_video_target(path: Path, settings: VideoSettings) -> None:
    """A named DisplayError unless ``path`` and ``settings`` can be written (no file opened)."""
    w, h = settings.size
    if w % 2 or h % 2:
        raise DisplayError(f"video size {w}x{h}: width and height must be even")
    if path.suffix.lower() not in CONTAINERS:
        raise DisplayError(
            f"video file {path}: unknown type {path.suffix!r}; use {', '.join(CONTAINERS)}"
        )
    if settings.alpha and path.suffix.lower() not in ALPHA_CONTAINERS:
        raise DisplayError(
            f"video file {path}: a transparent background needs a video with alpha: "
            "use .mov (ProRes 4444) or .webm (VP9)"
        )
    if not path.parent.is_dir():
        raise DisplayError(f"video file {path}: folder {path.parent} does not exist")


class VideoWriter:
    """Writes video frames and one stereo track to an MP4, encoding on a thread.

    PyAV releases the GIL while FFmpeg converts and encodes, so the thread runs beside the
    renderer. (A child process was tried: on a two-core machine it was slower, because the
    machine is short of cores, not of interpreter.)
    """

    def __init__(self, path: Path, settings: VideoSettings) -> None:
        path = Path(path)
        check_video_target(path, settings)
        try:
            self._enc = _Encoder(str(path), settings)
        except (OSError, ValueError) as exc:  # PyAV's errors are OSError subclasses
            raise DisplayError(f"cannot write video {path}: {exc}") from None
        self.path = path
        self.settings = settings
        self._queue: queue.Queue[np.ndarray | None] = queue.Queue(maxsize=3)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._loop, name="video-encode", daemon=True)
        self._thread.start()
        self.frames = 0

    def write_audio(self, stereo: np.ndarray) -> None:
        """The whole track, (N, 2) float32 at the settings' sample rate; once, before frames."""
        try:
            self._enc.write_audio(stereo)
        except (OSError, ValueError) as exc:
            raise DisplayError(f"cannot write video {self.path}: {exc}") from None

    def write(self, image: np.ndarray) -> None:
        """Queue one frame: (H*3/2, W) uint8 I420, top row first (see :meth:`Renderer.read_i420`),
        or (H, W, 4) uint8 RGBA in OpenGL row order (bottom row first).

        The array must not change afterwards: the worker thread reads it later.
        """
        w, h = self.settings.size
        if image.shape not in ((h * 3 // 2, w), (h, w, 4)) or image.dtype != np.uint8:
            raise DisplayError(
                f"video frame {image.shape} {image.dtype}: want uint8 ({h * 3 // 2}, {w}) I420 "
                f"or ({h}, {w}, 4) RGBA"
            )
        if self._error is not None:
            raise DisplayError(f"video encoding failed: {self._error}")
        self._queue.put(image)
        self.frames += 1

    def _loop(self) -> None:
        try:
            while (image := self._queue.get()) is not None:
                self._enc.write(image)
        except Exception as exc:  # surfaced on the caller's thread by write()/close()
            self._error = exc
            while self._queue.get() is not None:
                pass

    def close(self) -> None:
        self._queue.put(None)
        self._thread.join()
        if self._error is not None:
            self._enc.container.close()
            raise DisplayError(f"video encoding failed: {self._error}")
        try:
            self._enc.close()
        except (OSError, ValueError) as exc:
            raise DisplayError(f"cannot write video {self.path}: {exc}") from None
