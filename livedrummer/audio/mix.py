"""Mix a performance's drum sounds into one stereo buffer, sample-accurate at each onset.

Each onset picks a voice from its instrument, zone and hi-hat articulation
(:func:`voice_for`), a velocity layer and gain (:func:`~livedrummer.audio.synth.layer_for`) and
is added at ``round(time_s * sr)``, so a stroke's attack starts on the sample of its onset. A
hi-hat sound is cut (10 ms fade) where the next hi-hat stroke starts, as the closing cymbals
would. A cymbal choke (a grab: polyphonic aftertouch > 0, per kit piece as the body gets them
from :func:`~livedrummer.body.sample.kit_choke_times`) stops every stroke of that piece still
sounding: it plays on to the choke and fades out over :data:`GRAB_FADE_S` (5 ms, no click), so
the sound stops where the picture's cymbal stops swinging (:func:`choke_cut_s` is the rule,
shared with the SoundFont path). Pieces are panned by their x position in the kit (drummer's
perspective: hi-hat left), equal-power. The result is scaled down as a whole if it would clip
(no compressor, so relative levels stay true; :func:`fit_headroom` works through the track in
steps, and the caller may pass the buffer, a disk-backed one for an hour-long show, so no
temporary the size of the track is made). Limits: one Python step per onset (a 2-minute
groove mixes in well under a second); no effects; a grab is an instant stop of the ringing,
not a hand's gradual damping, and a release (aftertouch 0) does nothing.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from livedrummer.audio.synth import SAMPLE_RATE, layer_for, voice_layers
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone

CUT_FADE_S = 0.01  # a hi-hat stroke cut by the next one, or a sound cut by the track's end
GRAB_FADE_S = 0.005  # a choked cymbal: from the grab to silence
HEADROOM = 0.9
STEP = 1 << 20  # samples per step through a whole track (bounded temporaries)


def voice_for(instrument: str, zone: Zone, hihat: HiHat, kit: Kit | None = None) -> str:
    """The synthesized voice that sounds this stroke."""
    if instrument == "hihat":
        if hihat is HiHat.PEDAL or zone is Zone.PEDAL:
            return "hihat_pedal"
        return {HiHat.OPEN: "hihat_open", HiHat.HALF: "hihat_half"}.get(hihat, "hihat_closed")
    if instrument == "snare":
        return "click" if zone in (Zone.RIM, Zone.CROSS_STICK) else "snare"
    if instrument.startswith("tom"):
        piece = kit.resolve(instrument) if kit is not None else None
        radius = piece.radius_m if piece is not None else 0.19 - 0.02 * int(instrument[3:])
        return f"tom@{round(22.0 / radius)}"
    if instrument == "ride":
        return "ride_bell" if zone is Zone.BELL else "ride"
    if instrument in ("crash1", "crash2"):
        return "crash"
    if instrument == "percussion":
        return "block"
    return instrument  # kick, splash, china, cowbell, tambourine


def _pan(kit: Kit | None, instrument: str) -> tuple[float, float]:
    piece = kit.resolve(instrument) if kit is not None else None
    x = piece.position_m[0] if piece is not None else 0.0
    angle = (np.clip(x / 0.7, -1.0, 1.0) + 1.0) * np.pi / 4  # 0 = hard left, pi/2 = right
    return float(np.cos(angle)), float(np.sin(angle))


def choke_cut_s(
    onsets: np.ndarray, kit: Kit | None, chokes: Sequence[np.ndarray] | None
) -> np.ndarray:
    """Per onset, the time (s) of the first grab on its piece at or after it (inf: none).

    ``chokes`` holds one sorted array of grab times per piece of ``kit`` (the layout of
    :func:`~livedrummer.body.sample.kit_choke_times`); an onset's piece is the one ``kit``
    resolves its instrument to, as for the body. A grab at the very time of a stroke chokes
    it, as the body's cymbal channel does.
    """
    cut = np.full(len(onsets), np.inf)
    if chokes is None or not any(c.size for c in chokes):
        return cut
    if kit is None:
        raise ValueError("chokes are given per kit piece: pass the kit they belong to")
    if len(chokes) != len(kit.pieces):
        raise ValueError(f"chokes for {len(chokes)} pieces, kit {kit.name!r} has {len(kit.pieces)}")
    index = {p.name: k for k, p in enumerate(kit.pieces)}
    for code in np.unique(onsets["instrument"]).tolist():
        piece = kit.resolve(INSTRUMENTS[code])
        grabs = chokes[index[piece.name]] if piece is not None else None
        if grabs is None or not grabs.size:
            continue
        rows = np.flatnonzero(onsets["instrument"] == code)
        times = onsets["time_s"][rows].astype(np.float64)
        k = np.searchsorted(grabs, times, side="left")
        hit = k < grabs.size
        cut[rows[hit]] = grabs[k[hit]]
    return cut


def mix_onsets(
    onsets: np.ndarray,
    duration_s: float,
    kit: Kit | None = None,
    sr: int = SAMPLE_RATE,
    chokes: Sequence[np.ndarray] | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Stereo float32 (N, 2), N = round(duration_s * sr), with every onset's sound; a grab in
    ``chokes`` (per piece of ``kit``, see :func:`choke_cut_s`) stops its piece's sound. ``out``:
    the zeroed buffer to mix into and return (see :func:`track_buffer`), else a new one."""
    n = round(duration_s * sr)
    out = track_buffer(n, out)
    hat = INSTRUMENTS.index("hihat")
    hat_times = onsets["time_s"][onsets["instrument"] == hat]
    cuts = choke_cut_s(onsets, kit, chokes)
    grab_fade = max(1, round(GRAB_FADE_S * sr))
    pans: dict[str, tuple[float, float]] = {}
    for on, cut_s in zip(onsets, cuts.tolist(), strict=True):
        start = round(float(on["time_s"]) * sr)
        if start >= n or start < 0:
            continue
        instrument = INSTRUMENTS[int(on["instrument"])]
        voice = voice_for(instrument, ZONES[int(on["zone"])], HIHATS[int(on["hihat"])], kit)
        layer, gain = layer_for(int(on["velocity"]))
        sample = voice_layers(voice, sr)[layer]
        length = min(sample.size, n - start)
        if int(on["instrument"]) == hat:
            k = np.searchsorted(hat_times, float(on["time_s"]), side="right")
            if k < hat_times.size:
                length = min(length, round(float(hat_times[k]) * sr) - start)
        fade = min(length, int(CUT_FADE_S * sr))
        if cut_s < np.inf and round(cut_s * sr) - start + grab_fade < length:
            length = round(cut_s * sr) - start + grab_fade
            fade = grab_fade
        if length <= 0:
            continue
        piece = sample[:length] * gain
        if length < sample.size:
            piece[length - fade :] *= np.linspace(1.0, 0.0, fade, dtype=np.float32)
        if instrument not in pans:
            pans[instrument] = _pan(kit, instrument)
        left, right = pans[instrument]
        out[start : start + length, 0] += piece * left
        out[start : start + length, 1] += piece * right
    fit_headroom(out)
    return out


def track_buffer(n: int, out: np.ndarray | None = None) -> np.ndarray:
    """``out`` checked to be a C-contiguous (n, 2) float32 buffer, or a new one of zeros."""
    if out is None:
        return np.zeros((n, 2), np.float32)
    if out.shape != (n, 2) or out.dtype != np.float32 or not out.flags.c_contiguous:
        raise ValueError(
            f"track buffer {out.shape} {out.dtype}: want C-contiguous ({n}, 2) float32"
        )
    return out


def fit_headroom(out: np.ndarray) -> None:
    """Scale ``out`` down in place, as a whole, if its peak is above :data:`HEADROOM`."""
    peak = max(
        (float(np.abs(out[i : i + STEP]).max()) for i in range(0, len(out), STEP)), default=0.0
    )
    if peak > HEADROOM:
        for i in range(0, len(out), STEP):
            out[i : i + STEP] *= HEADROOM / peak
