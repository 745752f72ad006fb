"""``audio learn``'s listening loop: each drum hit about eight times, from an audio input.

The person is asked for one drum at a time; its hits are found by the recogniser's own onset
picking (:class:`~livedrummer.acoustic.learn.HitCollector`) and their band rises kept. Once
``hits`` have been heard and the input has been quiet for :data:`SETTLE_S` (so the last hit's
ring does not count as the next drum's first), the next drum is asked for. With ``channels``
(one microphone per drum) a drum's hits are taken from its own channel only. The result is
built by :func:`~livedrummer.acoustic.learn.build_profile`. A drum not heard within
``timeout_s`` is a :class:`~livedrummer.acoustic.learn.LearnError` naming it.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from livedrummer.acoustic.learn import HitCollector, LearnError, build_profile
from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.profile import AudioProfile, DetectorSettings

from .audioport import BLOCK, SAMPLE_RATE, AudioSource, find_device

SETTLE_S = 0.6


def learn_kit(
    device: str,
    drums: Sequence[int],
    name: str,
    hits: int = 8,
    channels: Mapping[int, int] | None = None,
    timeout_s: float = 60.0,
    say: Callable[[str], None] = print,
    settings: DetectorSettings | None = None,
) -> AudioProfile:
    import sounddevice as sd

    from livedrummer.timeline.clock import MonotonicClock

    # the same device checks as input --audio: missing, refused rate or channels
    AudioSource(device, MonotonicClock(), _placeholder(), channels).check()
    index = find_device(device)
    n_channels = max(channels) + 1 if channels else 1
    own = {cls: ch for ch, cls in channels.items()} if channels else {}
    blocks: queue.Queue[np.ndarray] = queue.Queue()

    def callback(data: np.ndarray, _frames: int, _time: Any, _status: Any) -> None:
        blocks.put(data.copy())

    rises: dict[int, np.ndarray] = {}
    with sd.InputStream(device=index, channels=n_channels, samplerate=SAMPLE_RATE,
                        blocksize=BLOCK, dtype="float32", callback=callback):  # fmt: skip
        for cls in drums:
            say(f"hit the {CLASSES[cls].replace('_', ' ')} about {hits} times")
            collector = HitCollector(SAMPLE_RATE, settings)
            found: list[np.ndarray] = []
            quiet = 0.0
            deadline = time.monotonic() + timeout_s
            while len(found) < hits or quiet < SETTLE_S:
                if time.monotonic() > deadline:
                    raise LearnError(
                        f"{CLASSES[cls]}: heard {len(found)} of {hits} hits in {timeout_s:g} s"
                    )
                try:
                    data = blocks.get(timeout=0.1)
                except queue.Empty:
                    continue
                mono = data[:, own[cls]] if cls in own else data.mean(axis=1)
                new = collector.process(mono.astype(np.float64))
                if len(found) < hits:
                    found += new[: hits - len(found)]
                quiet = 0.0 if new else quiet + len(data) / SAMPLE_RATE
            rises[cls] = np.array(found)
            say(f"  {CLASSES[cls]}: {len(found)} hits")
    return build_profile(name, rises, settings)


def _placeholder() -> AudioProfile:
    from livedrummer.acoustic.profile import load_profile

    return load_profile(None)
