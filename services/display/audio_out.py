"""The file window's sound: a pre-mixed drum track played through sounddevice, as the
transport says, and the clock the picture follows.

Design. The whole track is mixed before the window opens (the built-in kit,
:func:`~livedrummer.audio.mix.mix_onsets`, or a SoundFont's,
:func:`~livedrummer.audio.soundfont.render_soundfont`, with the cymbal chokes the body plays),
so the audio side only copies samples. The window and the sound share one clock, the output's
samples (:meth:`TrackPlayer.now`: the samples the device has taken, over the rate). The window
advances its transport by that clock and tells the player where the transport is with
:meth:`TrackPlayer.follow`: "at clock time ``at`` the position is ``t``, rolling or not".
The writer knows when the samples it writes are heard, so the sample heard at clock time
``c`` is the one of position ``t + (c - at)``, and the frame drawn for ``c`` shows the same
position. Between two requests the sound plays on sample by sample (no drift, no
resampling); a request that moves the position by more than :data:`JUMP_S` (a seek, a step,
a marker, the start) or starts or stops the sound is a jump, done as a :data:`FADE_S`
crossfade (no click), as are pause and play.

Limits: sound plays only forward at 1x; at other speeds and in reverse it fades out and is
muted (the window says so once in its log and in the readout) since a drum track resampled
or played backwards helps nobody study a stroke. No sound device (no PortAudio, no output):
:func:`open_player` returns ``None`` with one line saying so, and the window plays silently
on the monotonic clock. The writer is a Python thread: one starved for longer than the FIFO
(a very loaded machine) underruns, which :attr:`TrackPlayer.underruns` counts and the close
logs; the picture waits with the sound.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.audio.mix import mix_onsets
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.render.body_scene import BodyScene
from livedrummer.timeline.performance import Performance

from .output_latency import output_latency_s

log = logging.getLogger("livedrummer.display")

FADE_S = 0.005  # a jump, a pause or a start: crossfade this long
BUFFER_S = 0.05  # asked of PortAudio as the output latency: the FIFO the writer keeps full
MIN_WRITE = 256  # the writer waits until this many samples are free
WRITER_SLEEP_S = 0.004
SWITCH_S = 0.0005  # the interpreter's switch interval while a player runs (default 5 ms)
JUMP_S = 0.02  # a request this far from where the sound is moves it (less: play on)


@dataclass(frozen=True)
class Request:
    """At stream time ``at`` the track is at ``position_s``; ``rolling``: sounding at 1x."""

    position_s: float
    at: float
    rolling: bool


class TrackRenderer:
    """The sample-level part of the player, free of any device (tested alone): each
    :meth:`render` call fills one buffer whose first sample is heard at stream time ``dac``."""

    def __init__(self, track: np.ndarray, sr: int) -> None:
        if track.ndim != 2 or track.shape[1] != 2:
            raise ValueError(f"track {track.shape}: want (N, 2)")
        self.track = np.ascontiguousarray(track, np.float32)
        self.sr = sr
        self.fade_n = max(1, round(FADE_S * sr))
        self.pos: int | None = None  # sample index of the next sample; None: silent
        self.old: int | None = None  # the position faded out, during a crossfade
        self.fade_done = self.fade_n  # samples of the current crossfade done
        self.request: Request | None = None
        self.jumps = 0
        self.incoming: list[np.ndarray] = []  # one-shots to start (keys played, :meth:`hit`)
        self._shots: list[tuple[np.ndarray, int]] = []  # (sound, samples of it played)

    def hit(self, sound: np.ndarray) -> None:
        """Sound ``sound`` (N, 2) over the track from the next buffer on (a key played);
        safe from another thread (a list append)."""
        self.incoming.append(np.asarray(sound, np.float32))

    def _mix_shots(self, out: np.ndarray) -> None:
        while self.incoming:
            self._shots.append((self.incoming.pop(0), 0))
        kept = []
        for sound, done in self._shots:
            k = min(len(out), len(sound) - done)
            out[:k] += sound[done : done + k]
            if done + k < len(sound):
                kept.append((sound, done + k))
        self._shots = kept

    def _read(self, start: int, n: int) -> np.ndarray:
        out = np.zeros((n, 2), np.float32)
        lo, hi = max(start, 0), min(start + n, len(self.track))
        if hi > lo:
            out[lo - start : hi - start] = self.track[lo:hi]
        return out

    def _apply(self, request: Request, dac: float) -> None:
        target = (
            round((request.position_s + (dac - request.at)) * self.sr) if request.rolling else None
        )
        if (
            target is not None
            and self.pos is not None
            and abs(target - self.pos) <= JUMP_S * self.sr
        ):
            return  # on course: play on, sample by sample
        if target is None and self.pos is None:
            return
        self.old, self.pos, self.fade_done = self.pos, target, 0
        self.jumps += 1

    def render(self, n: int, dac: float, request: Request | None) -> np.ndarray:
        if request is not None and request is not self.request:
            self.request = request
            self._apply(request, dac)
        if self.fade_done >= self.fade_n:
            out = self._read(self.pos, n) if self.pos is not None else np.zeros((n, 2), np.float32)
        else:
            k = np.arange(self.fade_done, self.fade_done + n, dtype=np.float32)
            up = np.clip(k / self.fade_n, 0.0, 1.0)[:, None]
            out = np.zeros((n, 2), np.float32)
            if self.pos is not None:
                out += self._read(self.pos, n) * up
            if self.old is not None:
                out += self._read(self.old, n) * (1.0 - up)
                self.old += n
            self.fade_done += n
            if self.fade_done >= self.fade_n:
                self.old = None
        if self.pos is not None:
            self.pos += n
        if self.incoming or self._shots:
            self._mix_shots(out)
        return out


class TrackPlayer:
    """A sounddevice output stream fed from a :class:`TrackRenderer` (see the module docs).

    No Python runs in the audio thread: PortAudio's blocking stream keeps a FIFO that its own
    thread (JACK's process callback, ALSA's) empties, and a writer thread here keeps it full.
    The clock is the samples themselves: :meth:`now` is the count the device has taken from
    the FIFO (written minus queued) over the rate, less the output latency after the FIFO, so
    sample ``W`` of the stream is heard at clock time ``W / sr``, the ``dac`` time it is
    rendered for. This clock stops when the device stops taking samples (a stalled JACK
    graph, an underrun), and so does the picture; JACK's own frame-time estimate
    (``stream.time``) runs on through a stall and drifts by tens of ms on a loaded machine.
    A request takes effect after what is queued (:data:`BUFFER_S`, rounded up by PortAudio to
    a power of two of samples: 85 ms at 48 kHz), which a seek or a pause is heard late by; the
    picture is not moved."""

    def __init__(self, track: np.ndarray, sr: int, device: str | None = None) -> None:
        import sounddevice as sd

        self.renderer = TrackRenderer(track, sr)
        self.sr = sr
        self._request: Request | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.underruns = 0
        self.writes = 0
        self.written = 0  # samples written since the stream started
        self._stream = sd.OutputStream(
            samplerate=sr, channels=2, dtype="float32", device=device, latency=BUFFER_S
        )
        self._switch = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_S)  # the writer gets the interpreter back soon
        self._stream.start()
        self.latency_s = output_latency_s(self._stream)
        self.capacity = self._measure_capacity()
        self._thread = threading.Thread(target=self._write, name="window-sound", daemon=True)
        self._thread.start()

    def _measure_capacity(self) -> int:
        """The FIFO's size: what is free once it has drained (nothing is written yet)."""
        seen, deadline = -1, time.monotonic() + 0.5
        while time.monotonic() < deadline:
            now = self._stream.write_available
            if now == seen and now > 0:
                break
            seen = now
            time.sleep(0.03)
        return max(seen, 1)

    def _write(self) -> None:
        while not self._stop.is_set():
            free = self._stream.write_available
            if free < MIN_WRITE:
                time.sleep(WRITER_SLEEP_S)
                continue
            with self._lock:
                request = self._request
            block = self.renderer.render(free, self.written / self.sr, request)
            with self._lock:  # now() reads the count and the FIFO together
                underflow = self._stream.write(block)
                self.written += free
            if underflow:
                self.underruns += 1
            self.writes += 1

    def now(self) -> float:
        """The sample clock (seconds, see the class docs): the window's clock while it plays."""
        with self._lock:
            queued = max(self.capacity - self._stream.write_available, 0)
            return float((self.written - queued) / self.sr - self.latency_s)

    def follow(self, position_s: float, at: float, rolling: bool) -> None:
        """At stream time ``at`` the transport is at ``position_s``; sound it if ``rolling``."""
        with self._lock:
            old = self._request
            if old is not None and not old.rolling and not rolling:
                return  # still silent: nothing to tell
            self._request = Request(position_s, at, rolling)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self._stream.stop()
        self._stream.close()
        sys.setswitchinterval(self._switch)
        if self.underruns > 1:  # the first write after the FIFO drained at start counts one
            log.warning("window sound: %d buffer underruns", self.underruns)


def window_track(
    performance: Performance,
    body: BodyScene,
    soundfont: Path | None = None,
    sr: int = SAMPLE_RATE,
) -> np.ndarray:
    """The drum track of the window's transport (the performance and 1 s after), with the
    cymbal grabs and hi-hat closings cutting the sound (``sound_chokes``): the built-in kit,
    or ``soundfont``'s."""
    duration = performance.duration_s + 1.0
    if soundfont is not None:
        from livedrummer.audio.kitfile import render_kit_file

        return render_kit_file(
            performance.onsets, duration, soundfont, sr, body.kit, body.performed.sound_chokes
        )
    return mix_onsets(performance.onsets, duration, body.kit, sr, body.performed.sound_chokes)


def open_player(track: np.ndarray, sr: int, device: str | None) -> TrackPlayer | None:
    """A started player on ``device`` (a sounddevice name or substring; None: the default
    output), or None with one warning line when there is no sound output."""
    try:
        import sounddevice as sd
    except OSError as exc:
        log.warning(
            "no sound: %s (install libportaudio2): the window plays silently on the "
            "monotonic clock",
            exc,
        )
        return None
    try:
        return TrackPlayer(track, sr, device)
    except (sd.PortAudioError, ValueError) as exc:
        why = str(exc)
        if device is None and sd.default.device[1] < 0:
            why = "there is none"  # PortAudio's words: "Error querying device -1"
        log.warning(
            "no sound: cannot open the output %s (%s): the window plays silently on the "
            "monotonic clock",
            device or "(default)",
            why,
        )
        return None


def muted_reason(playing: bool, speed: float, reverse: bool) -> str | None:
    """Why the window's sound is muted while it plays, or None when it sounds."""
    if not playing:
        return None
    if reverse:
        return "sound muted in reverse"
    if speed != 1.0:
        return f"sound muted at {speed:g}x"
    return None
