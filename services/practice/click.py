"""The practice click: a PortAudio output stream that sounds clicks at shared-clock times.

As calibrate's click does, each click is placed by the stream's DAC time mapped onto the shared
clock (``time.monotonic``), so a click's time is when it leaves the speaker, not when Python
got round to it; the audio callback only reads an array the main thread replaces whole
(:meth:`ClickPlayer.schedule`), so no lock is taken in the callback. Accented clicks (each
bar's first beat) are higher and louder. Sounds (``--click-sound``):

- ``beep``: a sine burst, 1.5 kHz (accent 2.2 kHz), 15 ms;
- ``wood``: a woodblock-like knock, two inharmonic partials (0.9 and 2.4 kHz) decaying in 8 ms;
- ``cowbell``: two square-ish partials at 540 and 800 Hz, 60 ms.

``level`` (0 to 1) scales them all. Limits: the audio offset of calibration.toml is not
applied to the click (the player hears what the speaker plays; its delay is in the hits' input
offset when calibrated against this same click).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

SOUNDS = ("beep", "wood", "cowbell")
RATE = 48_000


def click_wave(sound: str, accent: bool, level: float) -> np.ndarray:
    """One click's samples (float32) at :data:`RATE`."""
    if sound == "beep":
        n = int(0.015 * RATE)
        t = np.arange(n) / RATE
        wave = np.sin(2 * np.pi * (2200.0 if accent else 1500.0) * t) * np.exp(-t * 300.0)
    elif sound == "wood":
        n = int(0.03 * RATE)
        t = np.arange(n) / RATE
        f = 1.15 if accent else 1.0
        wave = np.sin(2 * np.pi * 900.0 * f * t) + 0.6 * np.sin(2 * np.pi * 2400.0 * f * t)
        wave *= np.exp(-t / 0.008) / 1.6
    elif sound == "cowbell":
        n = int(0.06 * RATE)
        t = np.arange(n) / RATE
        f = 1.12 if accent else 1.0
        wave = np.tanh(3 * np.sin(2 * np.pi * 540.0 * f * t)) + np.tanh(
            3 * np.sin(2 * np.pi * 800.0 * f * t)
        )
        wave *= np.exp(-t / 0.02) / 2.0
    else:
        raise ValueError(f"click sound {sound!r}: one of {', '.join(SOUNDS)}")
    gain = level * (1.0 if accent else 0.6)
    out: np.ndarray = (gain * wave).astype(np.float32)
    return out


class ClickPlayer:
    """Clicks at shared-clock times through the default output (see the module docstring)."""

    def __init__(self, sound: str, level: float) -> None:
        import sounddevice as sd

        self.waves = (click_wave(sound, False, level), click_wave(sound, True, level))
        self._clicks: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros(0, dtype=bool))
        self.stream = sd.OutputStream(
            samplerate=RATE, channels=1, dtype="float32", callback=self._fill
        )
        self._offset = time.monotonic() - float(self.stream.time)
        self.stream.start()

    def schedule(self, times_s: np.ndarray, accents: np.ndarray) -> None:
        """Add clicks (shared-clock seconds); earlier ones already scheduled stay."""
        old_t, old_a = self._clicks
        t = np.concatenate([old_t, np.asarray(times_s, np.float64)])
        a = np.concatenate([old_a, np.asarray(accents, bool)])
        order = np.argsort(t, kind="stable")
        self._clicks = (t[order], a[order])

    def _fill(self, out: Any, frames: int, when: Any, _status: Any) -> None:
        times, accents = self._clicks
        start = float(when.outputBufferDacTime) + self._offset
        out[:, 0] = 0.0
        longest = max(w.size for w in self.waves) / RATE
        end = start + frames / RATE
        lo = int(np.searchsorted(times, start - longest))
        hi = int(np.searchsorted(times, end))
        for c, accent in zip(times[lo:hi].tolist(), accents[lo:hi].tolist(), strict=True):
            wave = self.waves[int(accent)]
            first = round((c - start) * RATE)  # sample of the buffer where the click starts
            a, b = max(0, first), min(frames, first + wave.size)
            if b > a:
                out[a:b, 0] += wave[a - first : b - first]

    def close(self) -> None:
        self.stream.stop()
        self.stream.close()
