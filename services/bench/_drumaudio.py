"""Test audio from real drum samples: GMD grooves through a General MIDI SoundFont.

For the recogniser's tests and ``bench transcribe``: an excerpt of a Groove MIDI Dataset
performance (CC BY 4.0; Gillick et al. 2019) is rendered through a sampled SoundFont (Debian's
``timgm6mb-soundfont``, :data:`DEFAULT_SF2`) by FluidSynth, as :mod:`livedrummer.audio.soundfont`
renders any drum track, then made less clean: a small room (a seeded exponentially decaying
noise tail, RT60 :data:`RT60_S`, mixed :data:`WET` below the direct sound) and white noise
:data:`NOISE_DB` below the loudest sample. One-microphone-per-drum stems render each piece
alone, then add every other piece to each stem :data:`LEAK_DB` down and 1 ms late (the other
drums heard from a close microphone's position). Everything is seeded, so a test's audio is
the same on every run. The ground truth is the excerpt's onsets as the MIDI file has them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.acoustic.pieces import CLASSES, classes_of
from livedrummer.audio.soundfont import render_soundfont

SR = 48_000
DEFAULT_SF2 = Path("/usr/share/sounds/sf2/TimGM6mb.sf2")
RT60_S = 0.35
WET = 0.25
NOISE_DB = -50.0
LEAK_DB = -20.0
#: The microphones of the one-per-drum rig, and the classes each one hears.
MICS: dict[str, tuple[str, ...]] = {
    "kick": ("kick",), "snare": ("snare",), "hihat": ("hihat_closed", "hihat_open"),
    "tom_high": ("tom_high",), "tom_mid": ("tom_mid",), "tom_low": ("tom_low",),
    "crash": ("crash",), "ride": ("ride",),
}  # fmt: skip


@dataclass(frozen=True)
class Excerpt:
    """Ground-truth onsets (ONSET_DTYPE, times from 0) of a groove excerpt, their classes."""

    name: str
    onsets: np.ndarray
    classes: np.ndarray
    duration_s: float


def excerpt(midi: Path, start_s: float, length_s: float) -> Excerpt:
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    perf = read_midi_file(midi, load_note_map("roland-td"))
    on = perf.onsets
    keep = (on["time_s"] >= start_s) & (on["time_s"] < start_s + length_s)
    part = on[keep].copy()
    part["time_s"] -= start_s
    part["time_s"] += 0.25  # a lead-in, so the first hit has silence before it
    return Excerpt(midi.stem, part, classes_of(part), length_s + 1.5)


def room(dry: np.ndarray, seed: int) -> np.ndarray:
    """``dry`` (n,) or (n, ch) in a small room: direct sound plus a decaying noise tail."""
    rng = np.random.default_rng(seed)
    n_ir = int(RT60_S * SR)
    t = np.arange(n_ir) / SR
    ir = rng.standard_normal(n_ir) * np.exp(-6.9 * t / RT60_S)
    ir[: int(0.004 * SR)] = 0.0  # the first reflections arrive 4 ms after the direct sound
    ir *= WET / np.sqrt(np.sum(ir**2))
    n = dry.shape[0] + n_ir
    size = 1 << int(np.ceil(np.log2(n)))
    spec_ir = np.fft.rfft(ir, size)
    cols = dry if dry.ndim == 2 else dry[:, None]
    wet = np.fft.irfft(np.fft.rfft(cols, size, axis=0) * spec_ir[:, None], size, axis=0)
    out = cols + wet[: dry.shape[0]]
    return out if dry.ndim == 2 else out[:, 0]


def add_noise(audio: np.ndarray, seed: int, noise_db: float = NOISE_DB) -> np.ndarray:
    rng = np.random.default_rng(seed + 1)
    peak = float(np.max(np.abs(audio))) or 1.0
    return audio + rng.standard_normal(audio.shape) * peak * 10 ** (noise_db / 20)


def render_mix(ex: Excerpt, sf2: Path = DEFAULT_SF2, seed: int = 0) -> np.ndarray:
    """Mono float32 mix of the excerpt, in a room, with noise."""
    stereo = render_soundfont(ex.onsets, ex.duration_s, sf2, SR)
    mono = stereo.mean(axis=1).astype(np.float64)
    out = add_noise(room(mono, seed), seed)
    return (out / max(1.0, float(np.max(np.abs(out))) / 0.9)).astype(np.float32)


def render_stems(
    ex: Excerpt, sf2: Path = DEFAULT_SF2, seed: int = 0, leak_db: float = LEAK_DB
) -> tuple[np.ndarray, list[str]]:
    """(n, mics) float32: one microphone per drum that the excerpt plays, with crosstalk;
    and the mics' names (keys of :data:`MICS`)."""
    names, dry = [], []
    n = round(ex.duration_s * SR)
    for mic, classes in MICS.items():
        codes = [CLASSES.index(c) for c in classes]
        mine = np.isin(ex.classes, codes)
        if not mine.any():
            continue
        names.append(mic)
        dry.append(render_soundfont(ex.onsets[mine], ex.duration_s, sf2, SR).mean(axis=1))
    stems = np.stack(dry, axis=1).astype(np.float64)[:n]
    delay = int(0.001 * SR)
    late = np.zeros_like(stems)
    late[delay:] = stems[:-delay]
    leak = 10 ** (leak_db / 20)
    mics = stems + leak * (late.sum(axis=1, keepdims=True) - late)
    out = add_noise(room(mics, seed), seed)
    return (out / max(1.0, float(np.max(np.abs(out))) / 0.9)).astype(np.float32), names
