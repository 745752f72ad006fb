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

Cuts (a cymbal grab, the closing hi-hat; :mod:`~livedrummer.audio.cuts`) reach the mixer as
:meth:`LiveMixer.cut` (a kit piece, the cut's show time and its sample): every voice of that
piece struck at or before the cut stops as the offline mix stops it (on to the cut, then
:data:`~livedrummer.audio.mix.GRAB_FADE_S` of fade, unless the next hi-hat stroke cut it
sooner). A cut is kept for a second, so a stroke that arrives after it, but was struck before
it, is cut too: the result does not hang on which of the two came first.

Limits: a live stream cannot be scaled as a whole, so a sum over full scale is clipped at 1
and counted in :attr:`LiveMixer.clipped`; a cut of a sound already rendered past it cannot be
taken back (it stops at once, from the next sample rendered). One Python step per voice and
block: a few dozen voices ringing at once cost well under a millisecond a block.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from livedrummer.audio.mix import CUT_FADE_S, GRAB_FADE_S, _pan, voice_for
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
    time_s: float = 0.0  # its stroke's show time (a cut stops the strokes at or before it)
    piece: int = -1  # its kit piece's index (-1: none, never cut)
    hat_len: int = -1  # samples it sounds before the next hi-hat stroke (-1: all of them)
    cut_s: float = math.inf  # the first cut at or after its stroke (show time, s)
    cut_at: int = 0  # and that cut's sample on the stream
    own: bool = False  # ``sample`` is its own copy (an SFZ voice's cuts shape it in place)


class LiveMixer:
    """See the module docstring."""

    def __init__(self, kit: Kit | None = None, sr: int = SAMPLE_RATE) -> None:
        self.kit = kit
        self.sr = sr
        self.voices: list[Voice] = []
        self.rendered = 0  # samples rendered so far: an onset before this starts late
        self.clipped = 0  # samples clipped at full scale
        self._pans: dict[str, tuple[float, float]] = {}
        self._piece = {p.name: k for k, p in enumerate(kit.pieces)} if kit is not None else {}
        self._cuts: list[tuple[int, float, int]] = []  # recent cuts: (piece, show time, sample)

    def piece_of(self, instrument: str) -> int:
        """The index of the kit piece ``instrument`` resolves to (-1: none, or no kit)."""
        piece = self.kit.resolve(instrument) if self.kit is not None else None
        return -1 if piece is None else self._piece[piece.name]

    def cut(self, piece: int, time_s: float, at: int) -> None:
        """A cut of ``piece`` at show time ``time_s``, sample ``at`` of the stream: every voice
        of the piece struck at or before it stops (see the module docstring)."""
        self._cuts = [c for c in self._cuts if c[2] > self.rendered - self.sr]
        self._cuts.append((piece, time_s, at))
        for v in self.voices:
            if v.piece == piece and v.time_s <= time_s < v.cut_s:
                self._cut_voice(v, time_s, at)

    def _cut_on_arrival(self, v: Voice) -> None:
        """A voice just added, struck before a cut that came first."""
        for piece, time_s, at in self._cuts:
            if piece == v.piece and v.time_s <= time_s < v.cut_s:
                self._cut_voice(v, time_s, at)

    def _cut_voice(self, v: Voice, time_s: float, at: int) -> None:
        v.cut_s, v.cut_at = time_s, max(at, self.rendered)  # what is rendered stays
        self._settle(v)

    def _settle(self, v: Voice) -> None:
        """Length and fade from the hi-hat cut and the grab, as :func:`mix_onsets` takes them:
        the grab where it is the shorter."""
        length = v.sample.size if v.hat_len < 0 else v.hat_len
        fade = min(length, int(CUT_FADE_S * self.sr)) if v.hat_len >= 0 else 0
        if v.cut_s < math.inf:
            grab_fade = max(1, round(GRAB_FADE_S * self.sr))
            grab = v.cut_at - v.start + grab_fade
            if grab < length:
                length, fade = grab, grab_fade
        v.length, v.fade = length, fade

    def add(self, onset: np.void | np.ndarray, start: int) -> None:
        """Sound ``onset`` (a row of ONSET_DTYPE) from sample ``start`` of the stream."""
        instrument = INSTRUMENTS[int(onset["instrument"])]
        hat = int(onset["instrument"]) == HAT
        voice = voice_for(
            instrument, ZONES[int(onset["zone"])], HIHATS[int(onset["hihat"])], self.kit
        )
        layer, gain = layer_for(int(onset["velocity"]))
        sample = voice_layers(voice, self.sr)[layer]
        if instrument not in self._pans:
            self._pans[instrument] = _pan(self.kit, instrument)
        left, right = self._pans[instrument]
        if hat:
            for v in self.voices:
                if v.hat and v.start <= start < v.start + (
                    v.sample.size if v.hat_len < 0 else v.hat_len
                ):
                    v.hat_len = start - v.start
                    self._settle(v)
        added = Voice(
            start,
            sample,
            gain,
            left,
            right,
            hat,
            sample.size,
            time_s=float(onset["time_s"]),
            piece=self.piece_of(instrument),
        )
        self.voices.append(added)
        self._cut_on_arrival(added)

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
