"""Mix a performance's drum sounds into one stereo buffer, sample-accurate at each onset.

Each onset picks a voice from its instrument, zone and hi-hat articulation
(:func:`voice_for`), a velocity layer and gain (:func:`~livedrummer.audio.synth.layer_for`) and
is added at ``round(time_s * sr)``, so a stroke's attack starts on the sample of its onset. A
hi-hat sound is cut (10 ms fade) where the next hi-hat stroke starts, as the closing cymbals
would. Pieces are panned by their x position in the kit (drummer's perspective: hi-hat left),
equal-power. The result is scaled down as a whole if it would clip (no compressor, so relative
levels stay true). Limits: one Python step per onset (a 2-minute groove mixes in well under a
second); no effects.
"""

from __future__ import annotations

import numpy as np

from livedrummer.audio.synth import SAMPLE_RATE, layer_for, voice_layers
from livedrummer.kit import Kit
from livedrummer.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone

CHOKE_FADE_S = 0.01
HEADROOM = 0.9


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


def mix_onsets(
    onsets: np.ndarray, duration_s: float, kit: Kit | None = None, sr: int = SAMPLE_RATE
) -> np.ndarray:
    """Stereo float32 (N, 2), N = round(duration_s * sr), with every onset's sound."""
    n = round(duration_s * sr)
    out = np.zeros((n, 2), np.float32)
    hat = INSTRUMENTS.index("hihat")
    hat_times = onsets["time_s"][onsets["instrument"] == hat]
    pans: dict[str, tuple[float, float]] = {}
    for on in onsets:
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
        if length <= 0:
            continue
        piece = sample[:length] * gain
        if length < sample.size:
            fade = min(length, int(CHOKE_FADE_S * sr))
            piece = piece.copy()
            piece[length - fade :] *= np.linspace(1.0, 0.0, fade, dtype=np.float32)
        if instrument not in pans:
            pans[instrument] = _pan(kit, instrument)
        left, right = pans[instrument]
        out[start : start + length, 0] += piece * left
        out[start : start + length, 1] += piece * right
    peak = float(np.abs(out).max()) if n else 0.0
    if peak > HEADROOM:
        out *= HEADROOM / peak
    return out
