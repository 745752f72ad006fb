"""``display --live --sound``: each onset the synth forwards, sounded at its show time.

The synth forwards every onset on its pose stream the moment it reads it, stamped with its
show time (onset + D; protocol kind SHOWN_ONSET), and every control likewise (SHOWN_CONTROL). A
process of its own (so the display's drawing never holds the interpreter the sound needs)
subscribes to those two kinds only, keeps a
small PortAudio output FIFO full (:data:`BUFFER_S`, rounded by PortAudio to a power of two of
samples: 512 at 48 kHz, 10.7 ms) from a :class:`~livedrummer.audio.live_mix.LiveMixer` (the
built-in kit; an SFZ kit's :class:`~livedrummer.audio.sfz_live.SfzLiveMixer` with
``--sfz``; a SoundFont's :class:`~livedrummer.audio.soundfont_live.SoundFontLiveMixer` with
``--soundfont``), and starts each onset on the sample a
:class:`~livedrummer.audio.stream_clock.StreamClock` says is heard at its show time. An onset
is held until the block its sample falls in is about to be written and mapped to its sample
then, not when it arrives (a D earlier): a slip of the device meanwhile (JACK's dummy driver on
a loaded machine) is then already in the clock. An onset whose sample was written already
starts on the next sample free and is counted late (D must exceed the bus latency plus the
FIFO: the default 30 ms does). A control is read through the note map (``--map``, the
synth's) into a cut (:class:`~livedrummer.audio.cuts.CutReader`: a cymbal grab, the hi-hat
pedal closing), held and placed the same way: the mixer applies it on the sample heard at its
show time, and the ringing cymbal or hi-hat stops when the picture's does.

One loop, no Python in the audio thread: wait on the socket (the one
:class:`~services.wire.stream_rx.StreamReceiver`, its sequence numbers not read: the subscription
takes two kinds of the stream only) for up to a millisecond, read what came, look at the
FIFO, top it up. :class:`LiveSound` starts and stops the process from the display; it waits
for the output to open and, where there is none, says so in one line and the display runs
silent. At the end the process reports its counts (onsets, late, underruns, clipped samples,
bad messages) and the parent logs them.

Limits: a remote synth's
CURVE keys are passed to the subscriber as the display has them.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import queue
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer.protocol import Kind, topic

from ..wire.net import Security
from ..wire.stream_rx import StreamReceiver
from .output_latency import output_latency_s, output_period

log = logging.getLogger("livedrummer.display")

BUFFER_S = 0.01  # asked of PortAudio as the output latency: the FIFO kept full
MIN_WRITE = 64  # samples free before a write
POLL_MS = 1
RATE = 48_000
_SOUND_KINDS = (Kind.SHOWN_ONSET, Kind.SHOWN_CONTROL)


@dataclass(frozen=True)
class SoundConfig:
    sub: str
    device: str | None = None
    kit: str = "rock5"
    security: Security = field(default_factory=Security)
    buffer_s: float = BUFFER_S
    sfz: str | None = None  # an SFZ kit instead of the built-in one
    soundfont: str | None = None  # a General MIDI SoundFont (FluidSynth) instead
    note_map: str = "roland-td"  # the synth's note map: which piece a grab is on, the pedal


@dataclass
class SoundStats:
    onsets: int = 0
    cuts: int = 0  # grabs and hi-hat closings applied
    late: int = 0  # onsets and cuts started after their show time (their sample was written)
    underruns: int = 0
    clipped: int = 0
    bad: int = 0
    latency_ms: float = 0.0  # the output's latency after the FIFO (StreamClock's)
    lead_ms: list[float] = field(default_factory=list)  # show time - write head, per onset

    def line(self) -> str:
        lead = np.percentile(self.lead_ms, [50, 1]) if self.lead_ms else [np.nan, np.nan]
        return (
            f"sound: {self.onsets} onsets, {self.cuts} cuts, {self.late} late, "
            f"{self.underruns} underruns, "
            f"{self.clipped} samples clipped, {self.bad} bad messages; onsets placed "
            f"{lead[0]:.1f} ms (p50) / {lead[1]:.1f} ms (p1) ahead of the output, "
            f"output latency {self.latency_ms:.2f} ms"
        )


def _capacity(stream: Any) -> int:
    seen, deadline = -1, time.monotonic() + 0.5
    while time.monotonic() < deadline:
        now = stream.write_available
        if now == seen and now > 0:
            break
        seen = now
        time.sleep(0.02)
    return max(seen, 1)


def sound_loop(config: SoundConfig, stop: Any, report: Any) -> None:
    """The process body: ``report`` (a queue) gets ("ready", None) or ("error", line), and
    ("stats", SoundStats) at the end; runs until ``stop`` (an Event) is set."""
    from livedrummer.audio.cuts import CutReader
    from livedrummer.audio.live_mix import LiveMixer
    from livedrummer.audio.stream_clock import StreamClock
    from livedrummer.kit.loader import load_kit
    from livedrummer.midi.notemap import load_note_map

    try:
        import sounddevice as sd

        stream = sd.OutputStream(
            samplerate=RATE,
            channels=2,
            dtype="float32",
            device=config.device,
            latency=config.buffer_s,
        )
        stream.start()
    except Exception as exc:  # PortAudioError, no library (OSError), no device (ValueError)
        report.put(
            (
                "error",
                f"no sound: cannot open the output {config.device or '(default)'}"
                f" ({exc}): the display runs silent",
            )
        )
        return
    stats = SoundStats()
    mixer: LiveMixer | None = None
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    # kinds filtered by the subscription: the numbers of the poses between them are not seen
    rx = StreamReceiver("sound stream", log, _SOUND_KINDS, sequenced=False)
    try:
        kit = load_kit(config.kit)
        cuts = CutReader(load_note_map(config.note_map), kit)
        if config.sfz is not None:
            from livedrummer.audio.sfz_live import SfzLiveMixer
            from livedrummer.audio.sfz_render import check_sfz

            mixer = SfzLiveMixer(check_sfz(Path(config.sfz)), kit, RATE)
        elif config.soundfont is not None:
            from livedrummer.audio.soundfont_live import SoundFontLiveMixer

            mixer = SoundFontLiveMixer(Path(config.soundfont), kit, RATE)
        else:
            mixer = LiveMixer(kit, RATE)
        # subscribed once the kit is loaded (a SoundFont takes a while): what came meanwhile
        # would queue and be read late
        rx.connect(
            ctx, config.sub, "sound sub", config.security, topics=[topic(k) for k in _SOUND_KINDS]
        )
        cap = _capacity(stream)
        clock = StreamClock(RATE, output_latency_s(stream), period=output_period(stream))
        stats.latency_ms = clock.latency_s * 1000
        written = 0
        clock.look(time.monotonic(), written, cap - stream.write_available)
        report.put(("ready", None))
        pending: list[Pending] = []  # read, not yet placed: (show time, onset row or cut)
        while not stop.is_set():
            if rx.poll(POLL_MS):
                clock.look(time.monotonic(), written, cap - stream.write_available)
                _read(rx, cuts, clock, written, pending, stats)
            now = time.monotonic()  # read before the FIFO (StreamClock.look)
            free = stream.write_available
            clock.look(now, written, cap - free)
            if free >= MIN_WRITE:
                _place(mixer, clock, written, written + free, pending, stats)
                if stream.write(mixer.render(free)):
                    stats.underruns += 1
                written += free
        stats.clipped = mixer.clipped
    finally:
        if mixer is not None:
            mixer.close()
        rx.close()
        ctx.term()
        stream.stop()
        stream.close()
        report.put(("stats", stats))


Pending = tuple[float, Any]  # (show time s, an onset row or a cut (piece, show time s))


def _read(
    rx: StreamReceiver,
    cuts: Any,
    clock: Any,
    written: int,
    pending: list[Pending],
    stats: SoundStats,
) -> None:
    """What is waiting: its onsets, and its controls read into cuts, onto ``pending``
    (placed as late as the FIFO allows, :func:`_place`: the clock is freshest then)."""
    batch = rx.drain()
    stats.bad += batch.bad
    for msg in batch.messages:
        if msg.kind is Kind.SHOWN_CONTROL:
            for row in msg.rows:
                cut = cuts.take(row)  # in arrival order: the pedal's state
                if cut is not None:
                    pending.append((cut[1], cut))
            continue
        for row in msg.rows:
            show = float(row["time_s"])
            stats.lead_ms.append((clock.sample_for(show) - written) / RATE * 1000)
            pending.append((show, row))


def _place(
    mixer: Any, clock: Any, written: int, end: int, pending: list[Pending], stats: SoundStats
) -> None:
    """Give the mixer, in arrival order, what is heard before sample ``end`` (the end of the
    block about to be written), each on the sample the clock maps its show time to now; one
    whose sample was written already starts at ``written`` and is counted late."""
    keep: list[Pending] = []
    for show, what in pending:
        at = clock.sample_for(show)
        if at >= end:
            keep.append((show, what))
            continue
        if at < written:
            stats.late += 1
            at = written
        if isinstance(what, tuple):
            mixer.cut(what[0], what[1], at)
            stats.cuts += 1
        else:
            mixer.add(what, at)
            stats.onsets += 1
    pending[:] = keep


class LiveSound:
    """The sound process, started and stopped by the display (see the module docstring)."""

    def __init__(self, config: SoundConfig) -> None:
        spawn = mp.get_context("spawn")
        self._stop = spawn.Event()
        self._report: Any = spawn.Queue()
        self._proc = spawn.Process(
            target=sound_loop,
            args=(config, self._stop, self._report),
            name="livedrummer-sound",
            daemon=True,
        )
        self.stats: SoundStats | None = None
        self.running = False

    def start(self, timeout_s: float = 30.0) -> bool:
        """Start and wait for the output to open: True, or False after one warning line."""
        self._proc.start()
        try:
            what, line = self._report.get(timeout=timeout_s)
        except queue.Empty:
            what, line = "error", "no sound: the sound process did not start"
        if what != "ready":
            log.warning("%s", line)
            self.close()
            return False
        self.running = True
        return True

    def close(self) -> None:
        self._stop.set()
        if self.running:
            try:
                what, stats = self._report.get(timeout=10.0)
                if what == "stats":
                    self.stats = stats
                    level = logging.WARNING if stats.late or stats.underruns else logging.INFO
                    log.log(level, "%s", stats.line())
            except queue.Empty:
                log.warning("sound: the sound process sent no summary")
        self._proc.join(5.0)
        if self._proc.is_alive():
            self._proc.kill()
        self.running = False
