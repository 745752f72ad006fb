"""Audio input source: microphones (or a mix) through PortAudio, recognised into onsets.

``input --audio DEVICE`` opens a PortAudio input stream through sounddevice (on JACK, ALSA or
whatever PortAudio was built with) at 48 kHz, 128-sample blocks, and runs the online
percussion recogniser (:class:`~livedrummer.acoustic.detector.OnlineDetector`) on the
daemon's thread: the PortAudio callback only copies each block into a bounded queue (overflows
are counted, never waited for), ``read`` drains it and returns the hits as onsets. From there
the daemon publishes and journals them exactly as a kit's notes, so everything downstream is
unchanged. Each hit is written as its class's General MIDI note on channel 10
(:mod:`livedrummer.acoustic.transcribe`).

Time. Sample ``n`` of the stream is placed on the shared clock at ``anchor + n / 48000``,
where ``anchor`` is the earliest (callback time - samples delivered so far / rate) among the
last :data:`ANCHOR_BLOCKS` blocks: the callback that ran soonest after its block was captured
sets it, so a late callback does not shift a hit, and an interface clock that runs a little
fast or slow against ``CLOCK_MONOTONIC`` (JACK's dummy backend on a loaded machine ran at 0.93
of real time) is followed within 0.17 s instead of drifting. A hit's stamp is its attack on
that scale, minus the stream's reported input latency; it is published ``lookahead`` frames
(5.3 ms) plus the attack's place in the onset window after the block that held it reached us.

``input --audio --trace FILE`` keeps, per hit, the clock times of the callback that brought
the block deciding it, of this thread taking that block, and of the detector giving the hit,
and writes them as JSON when the source closes (``bench transcribe --live`` reads them).

Problems: a device that does not exist, or refuses 48 kHz or the channel count, is a
:class:`~livedrummer.errors.MidiInputError` naming it and the input devices that exist
(``check`` before the show; the daemon reopens it every ``reconnect_s`` while absent).
Clipping, a silent input (10 s under -70 dBFS) and dropped blocks are counted and logged once
each; the daemon keeps running.
"""

from __future__ import annotations

import json
import logging
import queue
from collections import deque
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.acoustic.detector import OnlineDetector
from livedrummer.acoustic.model import HitModel
from livedrummer.acoustic.profile import AudioProfile
from livedrummer.acoustic.spectrum import HOP
from livedrummer.acoustic.transcribe import hits_to_onsets
from livedrummer.errors import MidiInputError
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import Onset

from .base import Event, Problems, Source

log = logging.getLogger("livedrummer.input")

SAMPLE_RATE = 48_000
BLOCK = 128
QUEUE_BLOCKS = 4096  # 11 s of audio: a stalled daemon loses blocks only after that
CLIP_LEVEL = 0.999
SILENCE_DBFS = -70.0
SILENCE_S = 10.0
ANCHOR_BLOCKS = 64
TRACE_BLOCKS = 256
TRACE_HITS = 1_000_000  # a trace keeps the first million hits (24 MB), then stops


def input_devices() -> list[str]:
    import sounddevice as sd

    return [str(d["name"]) for d in sd.query_devices() if int(d["max_input_channels"]) > 0]


def find_device(spec: str) -> int:
    """The index of the input device named ``spec`` (exact, a unique substring, or an
    index); MidiInputError naming the input devices otherwise."""
    import sounddevice as sd

    devices = list(sd.query_devices())
    inputs = [(i, str(d["name"])) for i, d in enumerate(devices) if d["max_input_channels"] > 0]
    if spec.isdigit() and any(i == int(spec) for i, _ in inputs):
        return int(spec)
    exact = [i for i, n in inputs if n == spec]
    hits = exact or [i for i, n in inputs if spec.lower() in n.lower()]
    if len(hits) == 1:
        return hits[0]
    names = ", ".join(repr(n) for _, n in inputs) or "none"
    why = "matches several" if hits else "no such audio input"
    raise MidiInputError(f"audio device {spec!r}: {why} (inputs: {names})")


class AudioSource(Source):
    """Onsets recognised from an audio input (see the module docstring)."""

    def __init__(
        self,
        device: str,
        clock: Clock,
        profile: AudioProfile,
        channels: Mapping[int, int] | None = None,
        performer: int = 0,
        problems: Problems | None = None,
        trace: Path | None = None,
        model: HitModel | None = None,
    ) -> None:
        super().__init__(f"audio {device}", clock, problems)
        self.device = device
        self.profile = profile
        self.performer = performer
        mapping = dict(channels) if channels else {}
        self.n_channels = max(mapping) + 1 if mapping else 1
        self._pick = sorted(mapping) if mapping else None
        classes = [mapping[c] for c in sorted(mapping)] if mapping else None
        self.detector = OnlineDetector(profile, SAMPLE_RATE, classes, model=model)
        self._queue: queue.Queue[tuple[float, np.ndarray]] = queue.Queue(QUEUE_BLOCKS)
        self._stream: Any = None
        self._delivered = 0  # samples handed to the detector
        self._received = 0  # samples the callback has seen
        self._anchors: deque[float] = deque(maxlen=ANCHOR_BLOCKS)
        self._latency_s = 0.0
        self._quiet_s = 0.0
        self._dropped = 0
        #: ``trace``: per hit, the clock times of its path through us (see :meth:`_trace`)
        self._trace_path = trace
        self._trace_rows: list[tuple[float, float, float]] = []
        self._blocks: deque[tuple[int, float, float]] = deque(maxlen=TRACE_BLOCKS)

    def check(self) -> None:
        import sounddevice as sd

        index = find_device(self.device)
        try:
            sd.check_input_settings(
                index, channels=self.n_channels, samplerate=SAMPLE_RATE, dtype="float32"
            )
        except sd.PortAudioError as exc:
            info = sd.query_devices(index)
            raise MidiInputError(
                f"audio device {info['name']!r} refuses {SAMPLE_RATE} Hz, {self.n_channels} "
                f"channel(s) ({exc}; it has {info['max_input_channels']} inputs, default rate "
                f"{info['default_samplerate']:g} Hz)"
            ) from None

    def open(self) -> None:
        import sounddevice as sd

        self.check()
        index = find_device(self.device)
        self.detector.reset()
        self._delivered = self._received = 0
        self._anchors.clear()
        self._queue = queue.Queue(QUEUE_BLOCKS)
        try:
            stream = sd.InputStream(
                device=index,
                channels=self.n_channels,
                samplerate=SAMPLE_RATE,
                blocksize=BLOCK,
                dtype="float32",
                latency="low",
                callback=self._callback,
            )
            stream.start()
        except sd.PortAudioError as exc:
            raise MidiInputError(f"audio device {self.device!r}: cannot open ({exc})") from None
        self._stream = stream
        self._latency_s = float(stream.latency or 0.0)
        self.is_open = True

    def _callback(self, data: np.ndarray, frames: int, _time: Any, status: Any) -> None:
        """PortAudio's thread: stamp and queue a copy, nothing else."""
        try:
            self._queue.put_nowait((self.clock.now(), data.copy()))
        except queue.Full:
            self._dropped += 1

    def read(self, timeout_s: float) -> list[Event]:
        if self._stream is not None and not self._stream.active:
            raise MidiInputError(f"audio device {self.device!r}: the stream stopped")
        blocks: list[np.ndarray] = []
        try:
            blocks.append(self._take(self._queue.get(timeout=timeout_s)))
            while True:
                blocks.append(self._take(self._queue.get_nowait()))
        except queue.Empty:
            pass
        if self._dropped:
            self.problems.report("audio blocks dropped", "the daemon fell behind", self._dropped)
            self._dropped = 0
        if not blocks:
            return []
        data = np.concatenate(blocks)
        self._watch(data)
        if self._pick is not None:
            data = data[:, self._pick]
        hits = self.detector.process(data)
        self._delivered += len(data)
        if not len(hits):
            return []
        if self._trace_path is not None:
            self._trace(hits)
        rows = hits_to_onsets(hits, self.performer)
        rows["time_s"] += min(self._anchors) - self._latency_s
        return [Onset.from_record(r) for r in rows]

    def _take(self, item: tuple[float, np.ndarray]) -> np.ndarray:
        stamp, data = item
        self._received += len(data)
        self._anchors.append(stamp - self._received / SAMPLE_RATE)
        if self._trace_path is not None:
            self._blocks.append((self._received, stamp, self.clock.now()))
        return data

    def _trace(self, hits: np.ndarray) -> None:
        """Per hit (in published order): when the callback got the block that decided it, when
        this thread took that block from the queue, and when the detector gave the hit."""
        done = self.clock.now()
        s = self.profile.settings
        if len(self._trace_rows) >= TRACE_HITS:
            return
        for t in np.sort(hits["time_s"]).tolist():
            decided = round((t + s.offset_ms / 1000.0) * SAMPLE_RATE) + s.lookahead * HOP
            block = next((b for b in self._blocks if b[0] >= decided), self._blocks[-1])
            self._trace_rows.append((block[1], block[2], done))

    def _watch(self, data: np.ndarray) -> None:
        peak = float(np.max(np.abs(data))) if data.size else 0.0
        clipped = int(np.count_nonzero(np.abs(data) >= CLIP_LEVEL))
        if clipped:
            self.problems.report(
                "clipping", f"{self.name}: input at full scale; turn it down", clipped
            )
        if peak < 10 ** (SILENCE_DBFS / 20):
            self._quiet_s += len(data) / SAMPLE_RATE
            if self._quiet_s >= SILENCE_S:
                what = f"no sound for {SILENCE_S:g} s (under {SILENCE_DBFS:g} dBFS)"
                self.problems.report("silence", f"{self.name}: {what}: is the input connected?")
                self._quiet_s = 0.0
        else:
            self._quiet_s = 0.0

    def close(self) -> None:
        import sounddevice as sd

        stream, self._stream = self._stream, None
        if stream is not None:
            try:
                stream.stop()
                stream.close()
            except sd.PortAudioError as exc:  # a vanished device may fail to close
                log.debug("closing %s: %s", self.name, exc)
        self.is_open = False
        if self._trace_path is not None:
            try:
                self._trace_path.write_text(json.dumps({"hits": self._trace_rows}))
            except OSError as exc:
                log.error("%s: cannot write the trace: %s", self._trace_path, exc.strerror or exc)
