"""An SFZ kit played live: the online twin of :func:`~livedrummer.audio.sfz_render.render_sfz`.

The same regions for each stroke (its General MIDI note, velocity, round robin count and
random number, drawn from the same seeded generator in arrival order, which is time order on
a live stream), the same pitch, gain and pan, and the same choke groups: a region with
``group`` G cuts what sounds with ``off_by`` G at its start, faded over the cut region's
``ampeg_release`` (at least 1 ms). A cut of the kit piece (a grab, the closing hi-hat:
:meth:`~livedrummer.audio.live_mix.LiveMixer.cut`) ends each of the piece's voices struck at or
before it as the offline render ends it: on to the cut, then
:data:`~livedrummer.audio.mix.GRAB_FADE_S` of fade. Each cut multiplies the voice's own copy
of its samples by its envelope (a ramp, then zeros), so the two kinds of cut combine as the
offline render combines them, whichever arrives first. Voices are mixed block by block by
:class:`~livedrummer.audio.live_mix.LiveMixer`. Limits: those of the live mixer (clipped, not
scaled, over full scale; what was rendered before a cut arrived stays).
"""

from __future__ import annotations

import zlib

import numpy as np

from livedrummer.audio.live_mix import LiveMixer, Voice
from livedrummer.audio.mix import GRAB_FADE_S, _pan
from livedrummer.audio.sfz import SfzKit
from livedrummer.audio.sfz_render import MIN_FADE_S, _pitched, choose, read_sample
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES
from livedrummer.midi.gm import gm_note, warm_note_tables


class SfzLiveMixer(LiveMixer):
    """See the module docstring."""

    def __init__(self, sfz: SfzKit, kit: Kit | None = None, sr: int = SAMPLE_RATE) -> None:
        super().__init__(kit, sr)
        self.sfz = sfz
        self.counts: dict[int, int] = {}
        self.rng = np.random.default_rng(zlib.crc32(str(sfz.path).encode()))
        warm_note_tables()  # now: on the first stroke it would make it late

    def add(self, onset: np.void | np.ndarray, start: int) -> None:
        instrument = INSTRUMENTS[int(onset["instrument"])]
        note = gm_note(
            int(onset["note"]), instrument, ZONES[int(onset["zone"])], HIHATS[int(onset["hihat"])]
        )
        velocity = int(onset["velocity"])
        count = self.counts.get(note, 0)
        self.counts[note] = count + 1
        regions = choose(self.sfz, note, velocity, count, float(self.rng.random()))
        for region in regions:
            if region.group == 0:
                continue
            for v in self.voices:
                if v.off_by == region.group and v.start < start < v.start + v.length:
                    fade = max(1, round(max(v.fade_s, MIN_FADE_S) * self.sr))
                    self._envelope(v, start - v.start, fade)
        if instrument not in self._pans:
            self._pans[instrument] = _pan(self.kit, instrument)
        piece_left, piece_right = self._pans[instrument]
        for region in regions:
            sample, rate = read_sample(self.sfz, region)
            wave = _pitched(
                sample, rate, self.sr, (note - region.keycenter) * 100.0 + region.tune_cents
            )
            gain = 10.0 ** (region.volume_db / 20.0) * (velocity / 127.0) ** 2
            angle = (np.clip(region.pan / 100.0, -1.0, 1.0) + 1.0) * np.pi / 4
            left = float(np.cos(angle)) * np.sqrt(2.0) * piece_left * gain
            right = float(np.sin(angle)) * np.sqrt(2.0) * piece_right * gain
            voice = Voice(
                start,
                wave,
                1.0,
                left,
                right,
                False,
                wave.size,
                off_by=region.off_by,
                fade_s=region.release_s,
                time_s=float(onset["time_s"]),
                piece=self.piece_of(instrument),
            )
            self.voices.append(voice)
            self._cut_on_arrival(voice)

    def _envelope(self, v: Voice, k: int, fade: int) -> None:
        """Multiply ``v``'s samples from ``k`` on by a ramp of ``fade`` samples down to 0 and
        zeros after it (its own copy: the sample is shared; ``fade`` 0: zeros from ``k``); its
        length ends there."""
        if not v.own:
            v.sample, v.own = v.sample.copy(), True
        k = max(k, self.rendered - v.start)
        ramp = np.linspace(1.0, 0.0, fade, dtype=np.float32)[: max(v.sample.size - k, 0)]
        v.sample[k : k + ramp.size] *= ramp
        v.sample[k + ramp.size :] = 0.0
        v.length = min(v.length, k + fade)

    def _cut_voice(self, v: Voice, time_s: float, at: int) -> None:
        """A grab or the closing hi-hat, as :func:`~livedrummer.audio.sfz_render.render_sfz`
        cuts a stroke: its sample's first ``cut + fade`` samples (at most all), the last
        ``fade`` of them faded (where there are that many)."""
        v.cut_s, v.cut_at = time_s, at
        fade = max(1, round(GRAB_FADE_S * self.sr))
        length = min(v.sample.size, max(at - v.start + fade, 0))
        if length >= fade:
            self._envelope(v, length - fade, fade)
        else:
            self._envelope(v, length, 0)
