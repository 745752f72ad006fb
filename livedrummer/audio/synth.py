"""A synthesized drum kit with velocity layers (SMED's pre-scaled audio kits, made in code).

Every voice (kick, snare, rim click, a tom of a given pitch, closed/half/open/pedal hi-hat,
crash, ride bow and bell, splash, china, cowbell, tambourine, woodblock) is a short recipe of
decaying sines, pitch sweeps, filtered noise and the inharmonic square-wave cluster analogue
drum machines use for metal. A voice is rendered at :data:`LAYERS` velocities; a louder layer
is not just louder but brighter (more noise and high partials, a harder click), which is what
makes velocity audible. The mixer picks the layer at or above a stroke's velocity and scales
it down the rest of the way, so level follows velocity exactly and timbre follows it in steps.

Everything is deterministic (a fixed seed per voice), float32 mono at the caller's sample rate,
peak-scaled so the top layer of each voice peaks at its nominal level. Limits: no SoundFont
playback, no round robin (repeated strokes of one velocity sound identical), no room sound.
"""

from __future__ import annotations

import functools
import zlib
from collections.abc import Callable

import numpy as np

SAMPLE_RATE = 48_000
#: Velocities (1..127) the layers are rendered at.
LAYERS: tuple[int, ...] = (40, 72, 100, 127)
#: Metal cluster frequencies (Hz), an inharmonic set in the style of analogue drum machines.
_METAL_HZ = (205.3, 304.4, 369.6, 522.7, 540.0, 800.0)


def _t(duration_s: float, sr: int) -> np.ndarray:
    return np.arange(int(duration_s * sr), dtype=np.float64) / sr


def _noise(n: int, seed: str) -> np.ndarray:
    return np.random.default_rng(zlib.crc32(seed.encode())).standard_normal(n)


def _smooth(x: np.ndarray, taps: int) -> np.ndarray:
    """A moving average: a cheap low-pass (``x - _smooth(x)`` is the matching high-pass)."""
    if taps <= 1:
        return x
    return np.convolve(x, np.ones(taps) / taps, mode="same")


def _sweep(t: np.ndarray, f_end: float, f_add: float, tau: float) -> np.ndarray:
    """sin of a pitch falling from f_end + f_add to f_end with time constant tau."""
    phase = 2 * np.pi * (f_end * t + f_add * tau * (1.0 - np.exp(-t / tau)))
    return np.sin(phase)


def _metal(t: np.ndarray, scale: float) -> np.ndarray:
    sq = sum(np.sign(np.sin(2 * np.pi * f * scale * t + i)) for i, f in enumerate(_METAL_HZ))
    x = np.asarray(sq, np.float64) / len(_METAL_HZ)
    out: np.ndarray = x - _smooth(x, 6)
    return out


def _kick(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    body = _sweep(t, 48.0, 120.0 + 60.0 * b, 0.035) * np.exp(-t / 0.32)
    click = _noise(t.size, seed) * np.exp(-t / 0.003) * (0.15 + 0.5 * b)
    return body + click


def _snare(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    tone = (np.sin(2 * np.pi * 185 * t) + 0.5 * np.sin(2 * np.pi * 330 * t)) * np.exp(-t / 0.07)
    n = _noise(t.size, seed)
    wires = (n - _smooth(n, 3)) * b + _smooth(n, 4) * (1.0 - b)
    out: np.ndarray = 0.6 * tone + (0.5 + 0.6 * b) * wires * np.exp(-t / (0.11 + 0.08 * b))
    return out


def _click(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    tone = np.sin(2 * np.pi * 520 * t) + 0.6 * np.sin(2 * np.pi * 1750 * t)
    return (tone + 0.4 * b * _noise(t.size, seed)) * np.exp(-t / 0.025)


def _tom(t: np.ndarray, b: float, seed: str, hz: float) -> np.ndarray:
    body = _sweep(t, hz, hz * (0.35 + 0.3 * b), 0.06) * np.exp(-t / 0.45)
    stick = _noise(t.size, seed) * np.exp(-t / 0.004) * 0.3 * b
    return body + stick


def _hat(t: np.ndarray, b: float, seed: str, decay: float) -> np.ndarray:
    n = _noise(t.size, seed)
    hiss = n - _smooth(n, 2 + int(3 * (1 - b)))
    out: np.ndarray = (0.7 * _metal(t, 2.6) + 0.6 * hiss) * np.exp(-t / decay)
    return out


def _cymbal(
    t: np.ndarray, b: float, seed: str, decay: float, scale: float, dark: int
) -> np.ndarray:
    n = _noise(t.size, seed)
    wash = n - _smooth(n, dark + int(4 * (1 - b)))
    attack = 1.0 + 1.5 * b * np.exp(-t / 0.02)
    out: np.ndarray = (0.6 * _metal(t, scale) + 0.7 * wash) * np.exp(-t / decay) * attack
    return out


def _ride(t: np.ndarray, b: float, seed: str, bell: bool) -> np.ndarray:
    ping = np.sin(2 * np.pi * (760 if bell else 2900) * t) + 0.5 * np.sin(2 * np.pi * 1130 * t)
    wash = _cymbal(t, b, seed, 1.4, 2.0, 3)
    return (1.0 if bell else 0.4) * ping * np.exp(-t / (0.9 if bell else 0.35)) + 0.35 * wash


def _cowbell(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    x = np.sign(np.sin(2 * np.pi * 540 * t)) + np.sign(np.sin(2 * np.pi * 800 * t))
    return _smooth(x, 3) * np.exp(-t / 0.12) * (0.6 + 0.4 * b)


def _tambourine(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    n = _noise(t.size, seed)
    out: np.ndarray = (n - _smooth(n, 2)) * np.exp(-t / 0.16) * (0.4 + 0.6 * b)
    return out


def _block(t: np.ndarray, b: float, seed: str) -> np.ndarray:
    return np.sin(2 * np.pi * 950 * t) * np.exp(-t / 0.03)


Recipe = Callable[[np.ndarray, float, str], np.ndarray]

#: voice name -> (duration s, nominal peak, recipe)
_RECIPES: dict[str, tuple[float, float, Recipe]] = {
    "kick": (0.7, 0.95, _kick),
    "snare": (0.5, 0.8, _snare),
    "click": (0.2, 0.5, _click),
    "hihat_closed": (0.25, 0.4, lambda t, b, s: _hat(t, b, s, 0.045)),
    "hihat_half": (0.5, 0.45, lambda t, b, s: _hat(t, b, s, 0.15)),
    "hihat_open": (1.2, 0.5, lambda t, b, s: _hat(t, b, s, 0.45)),
    "hihat_pedal": (0.15, 0.3, lambda t, b, s: _hat(t, b, s, 0.02)),
    "crash": (2.8, 0.6, lambda t, b, s: _cymbal(t, b, s, 1.1, 2.3, 2)),
    "splash": (1.0, 0.5, lambda t, b, s: _cymbal(t, b, s, 0.35, 3.0, 1)),
    "china": (2.0, 0.6, lambda t, b, s: _cymbal(t, b, s, 0.8, 1.6, 5)),
    "ride": (2.5, 0.45, lambda t, b, s: _ride(t, b, s, False)),
    "ride_bell": (2.5, 0.5, lambda t, b, s: _ride(t, b, s, True)),
    "cowbell": (0.5, 0.5, _cowbell),
    "tambourine": (0.5, 0.4, _tambourine),
    "block": (0.2, 0.5, _block),
}


def voice_names() -> tuple[str, ...]:
    """Fixed voices; toms are ``tom@HZ`` with any pitch."""
    return tuple(_RECIPES)


@functools.lru_cache(maxsize=256)
def voice_layers(voice: str, sr: int = SAMPLE_RATE) -> tuple[np.ndarray, ...]:
    """One float32 sample per velocity layer of ``voice`` (``LAYERS`` order)."""
    if voice.startswith("tom@"):
        hz = float(voice[4:])
        duration, peak = 0.9, 0.8
        recipe: Recipe = functools.partial(_tom, hz=hz)
    else:
        duration, peak, recipe = _RECIPES[voice]
    t = _t(duration, sr)
    fade = np.minimum(1.0, (t[-1] - t) / 0.01)  # no click at the sample's end
    layers = []
    for v in LAYERS:
        x = recipe(t, v / 127.0, voice) * fade
        layers.append(x / max(float(np.abs(x).max()), 1e-9))
    # Scale so the top layer peaks at the nominal level and lower layers by their velocity.
    return tuple(
        (x * peak * (v / 127.0) ** 1.2).astype(np.float32)
        for x, v in zip(layers, LAYERS, strict=True)
    )


def layer_for(velocity: int) -> tuple[int, float]:
    """Index of the layer for ``velocity`` and the gain that brings it to that velocity."""
    v = max(1, min(127, int(velocity)))
    i = next(k for k, lv in enumerate(LAYERS) if lv >= v)
    return i, (v / LAYERS[i]) ** 1.2
