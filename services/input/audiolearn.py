"""``audio learn``'s listening loop: each drum hit about eight times, from an audio input.

The person is asked for one drum at a time; its hits are found by the recogniser's own onset
picking (:class:`~livedrummer.acoustic.learn.HitCollector`) and their band rises kept. Once
``hits`` have been heard and the input has been quiet for :data:`SETTLE_S` (so the last hit's
ring does not count as the next drum's first), the next drum is asked for. With ``channels``
(one microphone per drum) a drum's hits are taken from its own channel only. The result is
built by :func:`~livedrummer.acoustic.learn.build_profile`. A drum not heard within
``timeout_s`` is a :class:`~livedrummer.acoustic.learn.LearnError` naming it.

``other_strokes`` (names of :data:`~livedrummer.acoustic.learn.OTHER_STROKES`: the side
stick, the ride bell) are asked for right after the plain strokes of their drum, when that
drum is learnt, with a prompt that says how to play them; each becomes a template of its drum
(``other_sounds``). They are optional: one not heard ``hits`` times within ``timeout_s`` is
kept from the hits it had if there were at least three, else skipped with a line saying so,
and the profile is written without it.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from livedrummer.acoustic.learn import (
    OTHER_STROKES,
    HitCollector,
    LearnError,
    build_profile,
    real_hits,
)
from livedrummer.acoustic.pieces import CLASS_CODE, CLASSES
from livedrummer.acoustic.profile import AudioProfile, DetectorSettings
from livedrummer.acoustic.spectrum import N_BANDS

from .audioport import BLOCK, SAMPLE_RATE, AudioSource, find_device

SETTLE_S = 0.6
#: Fewest hits an optional stroke is kept from when its time is up.
MIN_STROKE_HITS = 3


def learn_kit(
    device: str,
    drums: Sequence[int],
    name: str,
    hits: int = 8,
    channels: Mapping[int, int] | None = None,
    timeout_s: float = 60.0,
    say: Callable[[str], None] = print,
    settings: DetectorSettings | None = None,
    other_strokes: Sequence[str] = (),
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

    with sd.InputStream(
        device=index,
        channels=n_channels,
        samplerate=SAMPLE_RATE,
        blocksize=BLOCK,
        dtype="float32",
        callback=callback,
    ):
        return learn_blocks(blocks, drums, name, hits, own, timeout_s, say, settings, other_strokes)


def learn_blocks(
    blocks: queue.Queue[np.ndarray],
    drums: Sequence[int],
    name: str,
    hits: int = 8,
    own: Mapping[int, int] | None = None,
    timeout_s: float = 60.0,
    say: Callable[[str], None] = print,
    settings: DetectorSettings | None = None,
    other_strokes: Sequence[str] = (),
) -> AudioProfile:
    """:func:`learn_kit`'s asking and listening, on (frames, channels) blocks at
    :data:`SAMPLE_RATE` as they arrive in ``blocks``; ``own``: class code → its channel."""
    own = own or {}

    def listen(cls: int) -> list[np.ndarray]:
        """Rises of up to ``hits`` hits of drum ``cls`` (fewer when ``timeout_s`` is up)."""
        collector = HitCollector(SAMPLE_RATE, settings)
        found: list[np.ndarray] = []
        quiet = 0.0
        deadline = time.monotonic() + timeout_s
        while len(found) < hits or quiet < SETTLE_S:
            if time.monotonic() > deadline:
                return found
            try:
                data = blocks.get(timeout=0.1)
            except queue.Empty:
                continue
            mono = data[:, own[cls]] if cls in own else data.mean(axis=1)
            new = collector.process(mono.astype(np.float64))
            if len(found) < hits:
                found += new[: hits - len(found)]
            quiet = 0.0 if new else quiet + len(data) / SAMPLE_RATE
        return found

    rises: dict[int, np.ndarray] = {}
    others: dict[int, list[np.ndarray]] = {}
    for cls in drums:
        drum = CLASSES[cls]
        say(f"hit the {drum.replace('_', ' ')} about {hits} times")
        found = listen(cls)
        if len(found) < hits:
            raise LearnError(f"{drum}: heard {len(found)} of {hits} hits in {timeout_s:g} s")
        rises[cls] = np.array(found)
        say(f"  {drum}: {len(found)} hits")
        for stroke in (s for s in other_strokes if CLASS_CODE[OTHER_STROKES[s].drum] == cls):
            say(f"{OTHER_STROKES[stroke].prompt}, about {hits} times")
            found = listen(cls)
            kept = real_hits(np.array(found).reshape(len(found), N_BANDS))
            if len(kept) < MIN_STROKE_HITS:
                say(
                    f"  {stroke}: heard {len(kept)} of {hits} hits in {timeout_s:g} s: "
                    f"skipped (the profile has no {stroke} template)"
                )
                continue
            others.setdefault(cls, []).append(kept)
            say(f"  {stroke}: {len(found)} hits")
    return build_profile(name, rises, settings, other_sounds=others)


def _placeholder() -> AudioProfile:
    from livedrummer.acoustic.profile import load_profile

    return load_profile(None)
