"""Recording conditions for training and testing audio: rooms, microphone colourings, noise.

A kit's samples are only half of what a recogniser hears; the other half is where the kit
stands and how it is picked up. :func:`condition` draws, from a seeded generator, one
:class:`Conditions` (a room's reverberation time and wet level, a microphone's EQ, a
compressor's threshold, a noise floor) and :func:`apply` puts a dry track through it. Pure
numpy, seeded: the same seed gives the same audio on every machine.

The room is a synthetic impulse response: a direct sound, sparse early reflections in the first
20 ms, and an exponentially decaying noise tail of the drawn RT60, low-passed a little more as
it decays (air and walls absorb highs). The EQ is a smooth gain curve on a log-frequency axis
(a low shelf, a high shelf and one peak, each drawn within ±9 dB), applied by one FFT of the
whole track. The compressor is a feed-forward one on a 5 ms attack / 80 ms release envelope,
so a loud hit's attack still passes and its tail is lifted (what a drum bus compressor does).
Limits: one room per track (no per-drum placement), no distortion, no time-varying noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Conditions:
    """One recording's conditions (see the module docstring)."""

    rt60_s: float
    wet: float  # the tail's energy relative to the direct sound's, in amplitude
    low_db: float  # low shelf (below ~150 Hz)
    high_db: float  # high shelf (above ~6 kHz)
    peak_hz: float
    peak_db: float
    comp_threshold_db: float  # below the track's peak; 0 = no compression
    comp_ratio: float
    noise_db: float  # white noise below the track's peak


def condition(rng: np.random.Generator) -> Conditions:
    """A random set of conditions: RT60 0.1-1.0 s, EQ within ±9 dB, compression on half the
    tracks, noise 40-65 dB below the peak."""
    compress = bool(rng.random() < 0.5)
    return Conditions(
        rt60_s=float(rng.uniform(0.1, 1.0)),
        wet=float(rng.uniform(0.1, 0.5)),
        low_db=float(rng.uniform(-9, 9)),
        high_db=float(rng.uniform(-9, 6)),
        peak_hz=float(np.exp(rng.uniform(np.log(200), np.log(6000)))),
        peak_db=float(rng.uniform(-9, 9)),
        comp_threshold_db=float(rng.uniform(-24, -8)) if compress else 0.0,
        comp_ratio=float(rng.uniform(2, 6)),
        noise_db=float(rng.uniform(-65, -40)),
    )


def room_ir(rt60_s: float, wet: float, sr: int, rng: np.random.Generator) -> np.ndarray:
    """A room's impulse response: 1 at sample 0, early reflections, a decaying tail."""
    n = int(rt60_s * sr)
    t = np.arange(n) / sr
    tail = rng.standard_normal(n) * np.exp(-6.9 * t / rt60_s)
    # darker as it decays: a one-pole low-pass whose cut-off falls with time, done in steps
    for k in range(1, 4):
        start = int(n * k / 4)
        a = 0.3 * k
        seg = tail[start:]
        out = np.empty_like(seg)
        acc = 0.0
        for i in range(0, len(seg), 64):  # blocks: a per-block pole is enough here
            chunk = seg[i : i + 64]
            acc = (1 - a) * float(chunk.mean()) + a * acc
            out[i : i + 64] = (1 - a) * chunk + a * acc
        tail[start:] = out
    tail[: int(0.003 * sr)] = 0.0
    for _ in range(6):  # early reflections
        at = int(rng.uniform(0.002, 0.02) * sr)
        if at < n:
            tail[at] += rng.uniform(-1, 1) * 3.0
    tail *= wet / (np.sqrt(np.sum(tail**2)) or 1.0)
    tail[0] = 1.0
    return tail


def eq_gain(c: Conditions, freqs: np.ndarray) -> np.ndarray:
    """The microphone EQ of ``c`` as an amplitude gain at each of ``freqs`` (Hz)."""
    f = np.maximum(freqs, 1.0)
    lf = np.log2(f)
    low = c.low_db / (1 + np.exp(3 * (lf - np.log2(150.0))))
    high = c.high_db / (1 + np.exp(-3 * (lf - np.log2(6000.0))))
    peak = c.peak_db * np.exp(-0.5 * ((lf - np.log2(c.peak_hz)) / 0.5) ** 2)
    out: np.ndarray = 10 ** ((low + high + peak) / 20)
    return out


def _compress(x: np.ndarray, c: Conditions, sr: int) -> np.ndarray:
    if c.comp_threshold_db >= 0:
        return x
    peak = float(np.max(np.abs(x))) or 1.0
    thr = peak * 10 ** (c.comp_threshold_db / 20)
    block = 64
    n = len(x) // block * block
    env_in = np.abs(x[:n]).reshape(-1, block).max(axis=1)
    att = np.exp(-block / (0.005 * sr))
    rel = np.exp(-block / (0.080 * sr))
    env = np.empty_like(env_in)
    e = 0.0
    for i, v in enumerate(env_in.tolist()):
        e = att * e + (1 - att) * v if v > e else rel * e + (1 - rel) * v
        env[i] = e
    over = np.maximum(env / thr, 1.0)
    gain = over ** (1.0 / c.comp_ratio - 1.0)
    g = np.repeat(gain, block)
    g = np.concatenate([g, np.full(len(x) - n, g[-1] if len(g) else 1.0)])
    out: np.ndarray = x * g
    return out / (float(np.max(np.abs(out))) or 1.0) * peak


def apply(dry: np.ndarray, c: Conditions, sr: int, seed: int) -> np.ndarray:
    """``dry`` (n,) or (n, channels) through the room, EQ, compressor and noise of ``c``;
    scaled to a peak of 0.9 (float32, same shape)."""
    rng = np.random.default_rng(seed)
    cols = dry[:, None] if dry.ndim == 1 else dry
    cols = cols.astype(np.float64)
    ir = room_ir(c.rt60_s, c.wet, sr, rng)
    n = cols.shape[0]
    size = 1 << int(np.ceil(np.log2(n + len(ir))))
    spec = np.fft.rfft(cols, size, axis=0)
    spec *= (np.fft.rfft(ir, size) * eq_gain(c, np.fft.rfftfreq(size, 1 / sr)))[:, None]
    wet = np.fft.irfft(spec, size, axis=0)[:n]
    out = np.stack([_compress(wet[:, k], c, sr) for k in range(wet.shape[1])], axis=1)
    peak = float(np.max(np.abs(out))) or 1.0
    out += rng.standard_normal(out.shape) * peak * 10 ** (c.noise_db / 20)
    out *= 0.9 / (float(np.max(np.abs(out))) or 1.0)
    result = out.astype(np.float32)
    return result[:, 0] if dry.ndim == 1 else result
