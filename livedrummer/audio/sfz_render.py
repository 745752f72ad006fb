"""A drum track from an SFZ kit (``--sfz kit.sfz``): the regions of :mod:`~livedrummer.audio.sfz`
played from their samples, sample-accurate at each onset.

Which note: the onset's General MIDI note (:func:`~livedrummer.midi.gm.gm_notes`, as for
a SoundFont: SFZ drum kits are laid out on the GM drum map). Which regions: every region whose
key and velocity ranges hold the stroke, less those whose round robin is elsewhere: a region
with ``seq_length`` N plays on the strokes whose count on that note, modulo N, is its
``seq_position`` - 1; with ``lorand``/``hirand`` it plays when the stroke's random number (one
per stroke, drawn in [0, 1) from a generator seeded by the kit's path, so a render is
repeatable) falls in [lorand, hirand). Several regions that fit all sound (layers).

How it sounds: the sample (WAV, FLAC, anything libsndfile reads, through ``soundfile``),
mono or the mean of its channels, resampled by linear interpolation from its own rate and
pitched by ``(note - pitch_keycenter) * 100 + tune`` cents; gain ``volume`` dB times
``(velocity / 127)²``; panned by ``pan`` (equal power) and then by the kit piece's place as
the built-in kit is (:func:`~livedrummer.audio.mix.voice_for`'s mixer). Chokes: a region with
``group`` G cuts every sound still ringing whose region has ``off_by`` G (the closing hi-hat
cuts the open one) with that region's ``ampeg_release`` as the fade (at least 1 ms); a cymbal
grab (aftertouch; :func:`~livedrummer.audio.mix.choke_cut_s`) cuts its piece's sound with
:data:`~livedrummer.audio.mix.GRAB_FADE_S`. The track is scaled down as a whole if it would
clip.

Errors: a sample that is missing or that libsndfile cannot read is an
:class:`~livedrummer.audio.sfz.SfzError` naming the .sfz file, the line of its ``sample``
opcode and the sample's path. Limits: samples are read whole into memory (a drum kit's are
small); no filters, envelopes other than the release, or effects.
"""

from __future__ import annotations

import logging
import zlib
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

from livedrummer.audio.mix import GRAB_FADE_S, choke_cut_s, fit_headroom, track_buffer
from livedrummer.audio.sfz import Region, SfzError, SfzKit, load_sfz
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit

log = logging.getLogger(__name__)
MIN_FADE_S = 0.001


@lru_cache(maxsize=512)
def _read(path: Path) -> tuple[np.ndarray, int]:
    import soundfile as sf

    data, rate = sf.read(str(path), dtype="float32", always_2d=True)
    return np.ascontiguousarray(data.mean(axis=1), np.float32), int(rate)


def read_sample(kit: SfzKit, region: Region) -> tuple[np.ndarray, int]:
    """The region's sample as mono float32 and its rate; SfzError naming file, line, path."""
    try:
        return _read(region.sample)
    except Exception as exc:  # soundfile raises LibsndfileError, RuntimeError or OSError
        why = "no such file" if not region.sample.exists() else str(exc).splitlines()[0]
        raise SfzError(
            f"{kit.path}:{region.sample_line}: sample {region.sample}: cannot read it ({why})"
        ) from None


def check_sfz(path: Path) -> SfzKit:
    """Parse ``path`` and read every sample now (a bad kit fails before a long render);
    unknown opcodes are logged once, in one line."""
    kit = load_sfz(path)
    if not kit.regions:
        raise SfzError(f"{path}: no <region> in the kit")
    for region in kit.regions:
        read_sample(kit, region)
    if kit.unknown:
        names = ", ".join(f"{k} (line {v})" for k, v in sorted(kit.unknown.items()))
        log.warning("%s: opcodes not played: %s", path, names)
    return kit


def _pitched(sample: np.ndarray, rate: int, sr: int, cents: float) -> np.ndarray:
    step = rate / sr * 2.0 ** (cents / 1200.0)
    if abs(step - 1.0) < 1e-9:
        return sample
    at = np.arange(0.0, sample.size - 1, step)
    return np.asarray(np.interp(at, np.arange(sample.size), sample), np.float32)


def choose(kit: SfzKit, note: int, velocity: int, count: int, rand: float) -> list[Region]:
    """The regions one stroke plays: its ``count``-th on ``note`` (from 0), random ``rand``."""
    return [
        r
        for r in kit.regions
        if r.plays(note, velocity)
        and count % r.seq_length == r.seq_position - 1
        and r.lorand <= rand < (r.hirand if r.hirand < 1.0 else 1.0 + 1e-9)
    ]


def render_sfz(
    onsets: np.ndarray,
    duration_s: float,
    path: Path,
    sr: int = SAMPLE_RATE,
    kit: Kit | None = None,
    chokes: Sequence[np.ndarray] | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Stereo float32 (N, 2), N = round(duration_s * sr): ``onsets`` played on the SFZ kit at
    ``path`` (see the module docstring); placement and length as :func:`mix_onsets`'s."""
    from livedrummer.audio.mix import _pan
    from livedrummer.kit.vocabulary import INSTRUMENTS
    from livedrummer.midi.gm import gm_notes

    sfz = check_sfz(path)
    n = round(duration_s * sr)
    out = track_buffer(n, out)
    notes = gm_notes(onsets)
    cuts = choke_cut_s(onsets, kit, chokes)
    rng = np.random.default_rng(zlib.crc32(str(path).encode()))
    counts: dict[int, int] = {}
    # sounding voices: (start, end, region, buffer row slice) for the choke groups
    ringing: list[tuple[int, int, Region, np.ndarray, float, float]] = []
    order = np.argsort(onsets["time_s"], kind="stable")
    for i in order.tolist():
        on = onsets[i]
        start = round(float(on["time_s"]) * sr)
        if not 0 <= start < n:
            continue
        note, velocity = int(notes[i]), int(on["velocity"])
        count = counts.get(note, 0)
        counts[note] = count + 1
        regions = choose(sfz, note, velocity, count, float(rng.random()))
        for region in regions:  # a group's stroke cuts what its group turns off
            if region.group == 0:
                continue
            keep = []
            for v in ringing:
                v_start, v_end, v_region, piece, left, right = v
                if v_region.off_by == region.group and v_start < start < v_end:
                    _cut(out, v, start, max(v_region.release_s, MIN_FADE_S), sr)
                else:
                    keep.append(v)
            ringing = keep
        ringing = [v for v in ringing if v[1] > start]
        piece_pan = _pan(kit, INSTRUMENTS[int(on["instrument"])])
        for region in regions:
            sample, rate = read_sample(sfz, region)
            cents = (note - region.keycenter) * 100.0 + region.tune_cents
            wave = _pitched(sample, rate, sr, cents)
            gain = 10.0 ** (region.volume_db / 20.0) * (velocity / 127.0) ** 2
            angle = (np.clip(region.pan / 100.0, -1.0, 1.0) + 1.0) * np.pi / 4
            left = float(np.cos(angle)) * np.sqrt(2.0) * piece_pan[0] * gain
            right = float(np.sin(angle)) * np.sqrt(2.0) * piece_pan[1] * gain
            length = min(wave.size, n - start)
            cut_s = float(cuts[i])
            if cut_s < np.inf:
                fade = max(1, round(GRAB_FADE_S * sr))
                length = min(length, max(round(cut_s * sr) - start + fade, 0))
                wave = wave[:length].copy()
                if length >= fade:
                    wave[length - fade :] *= np.linspace(1.0, 0.0, fade, dtype=np.float32)
            piece = wave[:length]
            out[start : start + length, 0] += piece * left
            out[start : start + length, 1] += piece * right
            ringing.append((start, start + length, region, piece, left, right))
    fit_headroom(out)
    return out


def _cut(
    out: np.ndarray,
    voice: tuple[int, int, Region, np.ndarray, float, float],
    at: int,
    fade_s: float,
    sr: int,
) -> None:
    """Take back a ringing voice's samples after ``at``, fading it out over ``fade_s``."""
    start, end, _region, piece, left, right = voice
    fade = max(1, round(fade_s * sr))
    keep = np.ones(end - start, np.float32)
    k = at - start
    ramp = np.linspace(1.0, 0.0, fade, dtype=np.float32)[: max(end - at, 0)]
    keep[k : k + ramp.size] = ramp
    keep[k + ramp.size :] = 0.0
    removed = piece * (1.0 - keep[: piece.size])
    out[start : start + piece.size, 0] -= removed * left
    out[start : start + piece.size, 1] -= removed * right
