"""Reading a recording for ``transcribe``: any audio file FFmpeg reads, through PyAV.

PyAV is already a dependency (the video writer), and FFmpeg reads WAV, FLAC, AIFF, MP3, Ogg
and the audio of a video alike, so no new library is needed (soundfile would add libsndfile
for fewer formats). The file is decoded whole, converted to float32 at 48 kHz (the rate the
detector's hop is chosen for; :data:`SAMPLE_RATE`) keeping its channels, and checked: a file
that cannot be opened or decoded, has no audio stream, or holds no samples is an
:class:`AudioFileError` naming the file. Clipping is reported (count and share of samples at
full scale) for the caller to warn about: a clipped hit is still a hit.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.errors import LivedrummerError

SAMPLE_RATE = 48_000
CLIP_LEVEL = 0.999


class AudioFileError(LivedrummerError):
    """An audio file cannot be read, or holds no sound."""


@dataclass(frozen=True)
class Recording:
    samples: np.ndarray  # (n, channels) float32 at SAMPLE_RATE
    source_rate: int
    clipped: int  # samples (over all channels) at full scale

    @property
    def channels(self) -> int:
        return int(self.samples.shape[1])

    @property
    def duration_s(self) -> float:
        return float(self.samples.shape[0] / SAMPLE_RATE)


def read_audio(path: Path) -> Recording:
    import av

    name = str(path)
    if path.is_dir():
        raise AudioFileError(f"{name}: is a directory, not an audio file")
    if not path.exists():
        raise AudioFileError(f"{name}: no such file")
    try:
        container = av.open(name)
    except (av.FFmpegError, OSError) as exc:
        why = getattr(exc, "strerror", None) or exc
        raise AudioFileError(f"{name}: not an audio file FFmpeg can read ({why})") from None
    with container:
        if not container.streams.audio:
            raise AudioFileError(f"{name}: no audio stream")
        stream = container.streams.audio[0]
        source_rate = int(stream.rate or 0)
        channels = int(stream.codec_context.channels or 0)
        if channels < 1:
            raise AudioFileError(f"{name}: audio stream has no channels")
        parts: list[np.ndarray] = []
        resampler = av.AudioResampler(format="fltp", layout=stream.layout, rate=SAMPLE_RATE)
        try:
            for frame in container.decode(stream):
                for out in resampler.resample(frame):
                    parts.append(out.to_ndarray())
            for out in resampler.resample(None):
                parts.append(out.to_ndarray())
        except av.FFmpegError as exc:
            why = getattr(exc, "strerror", None) or exc
            raise AudioFileError(f"{name}: cannot decode its audio ({why})") from None
    if not parts or sum(p.shape[1] for p in parts) == 0:
        raise AudioFileError(f"{name}: holds no audio samples")
    samples = np.ascontiguousarray(np.concatenate(parts, axis=1).T, np.float32)
    clipped = int(np.count_nonzero(np.abs(samples) >= CLIP_LEVEL))
    return Recording(samples, source_rate, clipped)
