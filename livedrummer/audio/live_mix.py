"""The built-in kit played live: onsets added as they arrive, the sound rendered block by block.

The online twin of :func:`~livedrummer.audio.mix.mix_onsets`: each onset picks the same voice,
velocity layer, gain and pan and starts on its sample (:meth:`LiveMixer.add`, a sample index
on the output stream); :meth:`LiveMixer.render` adds every voice sounding in a block. A
hi-hat stroke cuts the hi-hat still ringing, faded over the :data:`~livedrummer.audio.mix.
CUT_FADE_S` before the new stroke as the offline mix does, for the part of the fade not yet
rendered (the new stroke arrives ``D`` before it sounds, so normally all of it). The result
is the offline mix, block for block, wherever the offline one was not scaled for headroom.

An SFZ kit plays live the same way (:class:`~livedrummer.audio.sfz_live.SfzLiveMixer`, the
twin of :func:`~livedrummer.audio.sfz_render.render_sfz`), and a SoundFont through FluidSynth
(:class:`~livedrummer.audio.soundfont_live.SoundFontLiveMixer`).

Limits: no cymbal chokes (a grab arrives as a control, not yet forwarded to displays); a live
stream cannot be scaled as a whole, so a sum over full scale is clipped at 1 and counted in
:attr:`LiveMixer.clipped`. One Python step per voice and block: a few dozen voices ringing
at once cost well under a millisecond a block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.audio.mix import CUT_FADE_S, _pan, voice_for
from livedrummer.audio.synth import SAMPLE_RATE, layer_for, voice_layers
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES

HAT = INSTRUMENTS.index("hihat")


@dataclass
class Voice:
    start: int  # sample index of its first sample
    sample: np.ndarray  # the layer's samples (float32, mono)
    gain: float
    left: float
    right: float
    hat: bool
    length: int  # samples it sounds (cut by the next hi-hat)
    fade: int = 0  # the last ``fade`` of ``length`` samples fade to silence
    off_by: int = 0  # an SFZ region's choke: a stroke of this group cuts it (0: none)
    fade_s: float = 0.0  # an SFZ region's release: the fade when it is cut


class LiveMixer:
    """See the module docstring."""

    def __init__(self, kit: Kit | None = None, sr: int = SAMPLE_RATE) -> None:
        self.kit = kit
        self.sr = sr
        self.voices: list[Voice] = []
        self.rendered = 0  # samples rendered so far: an onset before this starts late
        self.clipped = 0  # samples clipped at full scale
        self._pans: dict[str, tuple[float, float]] = {}

    def add(self, onset: np.void | np.ndarray, start: int) -> None:
        """Sound ``onset`` (a row of ONSET_DTYPE) from sample ``start`` of the stream."""
        instrument = INSTRUMENTS[int(onset["instrument"])]
        hat = int(onset["instrument"]) == HAT
        voice = voice_for(instrument, ZONES[int(onset["zone"])], HIHATS[int(onset["hihat"])],
                          self.kit)  # fmt: skip
        layer, gain = layer_for(int(onset["velocity"]))
        sample = voice_layers(voice, self.sr)[layer]
        if instrument not in self._pans:
            self._pans[instrument] = _pan(self.kit, instrument)
        left, right = self._pans[instrument]
        if hat:
            for v in self.voices:
                if v.hat and v.start <= start < v.start + v.length:
                    v.length = start - v.start
                    v.fade = min(v.length, int(CUT_FADE_S * self.sr))
        self.voices.append(Voice(start, sample, gain, left, right, hat, sample.size))

    def render(self, n: int) -> np.ndarray:
        """The next ``n`` samples of the stream, stereo float32 (n, 2)."""
        lo, hi = self.rendered, self.rendered + n
        out = np.zeros((n, 2), np.float32)
        keep: list[Voice] = []
        for v in self.voices:
            end = v.start + v.length
            a, b = max(lo, v.start), min(hi, end)
            if b > a:
                piece = v.sample[a - v.start : b - v.start] * v.gain
                if v.fade and v.length < v.sample.size:
                    ramp = np.linspace(1.0, 0.0, v.fade, dtype=np.float32)
                    k = np.arange(a - v.start, b - v.start) - (v.length - v.fade)
                    inside = k >= 0
                    piece[inside] *= ramp[k[inside]]
                out[a - lo : b - lo, 0] += piece * v.left
                out[a - lo : b - lo, 1] += piece * v.right
            if end > hi:
                keep.append(v)
        self.voices = keep
        self.rendered = hi
        over = np.abs(out) > 1.0
        if over.any():
            self.clipped += int(over.sum())
            np.clip(out, -1.0, 1.0, out=out)
        return out

    def close(self) -> None:
        """Free what the mixer holds (a SoundFont's synth; nothing here)."""
