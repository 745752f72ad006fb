"""Hits from audio: SuperFlux onsets, online peak picking, templates with fixed NMF bases.

**Three layers, one path.** :class:`OnlineDetector` is the detector: ``reset()`` and
``process(block)`` (float32 samples, ``(n,)`` or ``(n, channels)``, any block size) return the
hits decided in that block. :func:`detect` is its offline twin: the whole signal pushed as
one block (plus :data:`tail_samples` of silence, so the last hits are decided too). Frames go
through :func:`~.spectrum.frames_at` in batches whatever the block size, so the twins give the
same hits; the online one gives each hit ``L`` frames after the frame that saw its attack.

**Onsets.** A causal 256-sample spectrum every 128 samples (2.67 ms at 48 kHz); the onset
function is SuperFlux (log magnitudes, each bin's rise over the max of its neighbours two
frames earlier, summed). Frame ``p`` is an onset when its value is above every value in the
last :data:`PRE_MAX_S` and not below the ``lookahead`` frames after it (the profile's setting,
2 by default: the only future the online twin waits for), above the mean of the last 100 ms
plus ``delta``, above ``floor``, at least :data:`COMBINE_S` after the previous onset, and,
within 32 ms of it, at least :data:`CLOSE_SHARE` of its value (a second drum, not the first
one's decay). A mix: 15 and 10 ms windows, since a drummer's kick and hi-hat land 5-25 ms
apart, and a drum is not reported twice within 32 ms; one microphone per drum: 6 ms (another
drum's crosstalk just before must not hide the channel's own); one drum at a time (learning):
30 ms. A rise out of digital silence (the reference frame's oldest hop all zeros: a stream's
or a file's start) counts :data:`FROM_SILENCE` of its value: noise starting
with a file or a player is no attack (half-silent reference frames too: noise starting in the
middle of a frame still rises out of nothing two frames on).

**A second onset function for the hi-hat** (a mix only). A drummer's hi-hat often lands 3-15 ms
after a snare or kick stroke; the full-band function's picking windows and the louder drum's
onset hide it, and the rise read at the louder drum's onset is over before the hat starts. So
a mix also picks peaks on the SuperFlux of the bands above :data:`HIGH_HZ` alone (8.8 kHz: the
hat's, where a snare's noise has faded 5 ms after its attack) with a 6 ms pre-max window, at
:data:`HIGH_DELTA` and :data:`HIGH_FLOOR` times the full-band thresholds, and at least
:data:`HIGH_GAP_S` after a full-band onset. Its onsets are classified as any other but report
only the strongest of :data:`HIGH_CLASSES` (hi-hats, crash, ride): the earlier drum's ring,
still growing in the 21 ms spectrum, is not a second stroke of it. Such a hit is stamped 0-8 ms
late (the hat's rise in the high bands peaks after its attack's first frame).

**Classes: templates as fixed NMF bases.** A hit's feature is what it *adds* to the 21 ms band
spectrum: bands ``L`` frames after the onset minus bands two frames before it, clipped at
zero, so a cymbal still ringing from an earlier hit is subtracted away. The feature is
explained as a non-negative sum of the profile's templates (KL-divergence multiplicative
updates, 60 iterations; the bases stay fixed, only activations are solved): this is why NMF
with fixed bases rather than nearest-template matching — a kick and a hi-hat struck together
are a sum of two templates, and the solve gives both activations; the strongest class, and
every class whose activation is at least ``poly`` of its own full-strength ``level`` (and
``min_level``), is a hit. Templates are a few numbers per drum, so learning a kit is a few
hits per drum (:mod:`.learn`), where trained models would need a corpus. Velocity:
``127 * sqrt(activation / level)`` with ``level`` the profile's full-strength activation (a
SoundFont's amplitude grows about as velocity squared).

**One microphone per drum** (``channels`` given): each channel has its own onset function and
its own class; crosstalk is rejected by comparing, at the same instant, the band rise each
channel saw: from channel ``c``'s rise, band by band, ``leak`` times the largest rise any other
channel saw is taken away (``leak``: the loudest crosstalk the profile allows, in amplitude;
0.15 by default), and the onset is dropped when less than :data:`OWN_SHARE` of it is left (a
hi-hat's high bands survive a kick heard through its microphone; the kick's own leak does
not), unless what is left is a soft hit of the channel's own drum (:data:`OWN_LEVEL`).
*A second look after crosstalk*: a drum struck 3-15 ms after a louder one on another channel
(a crash on a snare's backbeat) is first heard on its microphone as that drum's crosstalk; the
crosstalk's onset is dropped, and the channel's own attack, still inside the picking window of
the crosstalk's larger peak, would be lost with it. So for :data:`RESCUE_S` after a dropped
onset, a frame that tops the frames the decision waits for is the channel's own drum when
crosstalk explains less than half its rise (:data:`RESCUE_SHARE`) and what is left is
:data:`RESCUE_LEVEL` of the drum's full-strength level; its velocity is read from what is left.
A hi-hat's or cymbal's channel picks its onsets from its bands above :data:`MIC_HIGH_HZ` only.
*Ringing cymbals* (the crash and the ride, :data:`RING`): a stroke on a still-ringing cymbal
rises little above the ring, and the ring itself wobbles (a SoundFont's crash bumps 150-300 ms
after each stroke). So such a channel is picked at a share of the floor and delta
(:class:`Ring`) and an onset there is kept only when the channel's level above
:data:`MIC_HIGH_HZ` (the mean log band) in the ``lookahead`` frames after it tops its mean over
the :data:`RING_BEFORE` frames before it by the piece's ``jump``: a stroke lifts the ring it
lands on, the ring's wobble rises and falls back. The ride (often struck softly) is picked at
half the floor and delta with a 0.06 jump; the crash (loud, with a wider wobble) at half the
floor, the full delta and a 0.1 jump. Out of digital silence (a level of 0 in those frames)
the cymbal is not ringing and the plain thresholds apply. All of this reads only frames the
decision already waits for, so the latency and the twins are unchanged. Velocity as above,
from the channel's rise.

**Steady noise is no hit.** The onset function works on log magnitudes, so the frame-to-frame
jitter of a steady noise (a preamp's hiss, a fan, a room) rises as much at -30 dBFS as at -50:
white noise at -30 dBFS gave a mix 7-8 hits a second and a hi-hat's microphone 4-6, most of
them from the high bands, whose few bins jitter most. A stroke lifts the level it lands on;
jitter does not. So an onset on a hi-hat's microphone, and a mix's onset on its high-band
function, is kept only when the mean log band of those bands in the ``lookahead`` frames after
it tops its mean over the :data:`RING_BEFORE` frames before it by :data:`HIGH_LIFT` (the
ringing cymbals' check, at a larger jump); and a ringing cymbal's onset also needs the 21 ms
band spectrum's total to rise by :data:`RING_BAND_LIFT` (log10), which its wobble seldom does.
Not checked on a kick's, snare's or tom's microphone nor a mix's full-band onsets: there every
lift tried lost soft kicks under a snare's decay (a kick's energy is below the onset function's
bands), and their noise hits are rare (a snare's microphone, white noise at -30 dBFS: 0.7 a
second; at -50 dBFS: 1 in 20 s).

Limits: the lookahead is ``lookahead`` frames (5.3 ms) plus the attack's position in the
256-sample window (up to 5.3 ms): decisions come 5.3-10.7 ms after the attack, times are
corrected by ``offset_ms``; a drum found by the second look after crosstalk is stamped and
decided up to :data:`RESCUE_S` later than its attack; a drum hit while a louder one of the same
spectrum rings is missed; three toms are told apart by pitch only as well as their templates
differ. A soft ride stroke (velocity 30-40) on a ride still ringing from a louder one lifts its
level by less than the jump and is missed; a crash touched at velocity 15 or less under the
other drums' crosstalk is not heard at all.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from livedrummer.acoustic.model import (
    PICK_DELTA,
    PICK_FLOOR,
    HitModel,
    RecordingNorm,
    hit_features,
    model_input,
)
from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.profile import AudioProfile
from livedrummer.acoustic.spectrum import (
    CLASS_SIZE,
    FLUX_BANDS,
    FLUX_SIZE,
    HOP,
    N_BANDS,
    bands,
    flux_edges,
    frames_at,
    log_flux_spectra,
    superflux,
)

HIT_DTYPE = np.dtype(
    [("time_s", "<f8"), ("cls", "<i2"), ("velocity", "u1"), ("level", "<f4"), ("channel", "u1")]
)
BEFORE = 2  # the "before" band spectrum: frames before the onset frame
MU = 2  # SuperFlux: compare with the frame this many hops earlier
#: Peak picking windows: before an onset, its value must top the last PRE_MAX_S, and the last
#: onset must be COMBINE_S back. A mix: 15 and 10 ms, since a drummer's kick and hi-hat land
#: 5-25 ms apart and the second must be an onset of its own; a drum is still not reported twice
#: within SAME_DRUM_S. One microphone per drum: 6 ms, since the crosstalk of a louder drum
#: 5-25 ms earlier is an onset on every channel that must not hide the channel's own drum (its
#: own decay is held off by CLOSE_SHARE). One drum at a time (learning): 30 ms (a drum is not
#: struck twice faster).
PRE_MAX_S = {"mix": 0.015, "mics": 0.006, "one_drum": 0.030}
PRE_AVG_S = 0.100
COMBINE_S = {"mix": 0.010, "mics": 0.006, "one_drum": 0.030}
SAME_DRUM_S = 0.030
#: An onset within SAME_DRUM_S of the last must be at least this share of its value: a second
#: drum struck just after the first is as strong, the first one's own decay bumps are not.
CLOSE_SHARE = 0.5
#: The strongest drum of an onset is reported from this share of its full-strength level
#: (velocity 127 * sqrt(0.005) = 9); below it the onset is a ring's wobble, not a hit.
QUIETEST = 0.005
NMF_ITERATIONS = 60
#: A rise out of digital silence (the SuperFlux reference frame's oldest hop all zeros: a
#: stream's or a file's start, a player starting) counts at this share: the noise floor
#: starting out of nothing is not an attack (noise 50 dB down rises by up to 2.7 on a cymbal's
#: channel: 0.4 at this share, under its floor of 0.6); a drum hit out of silence still is,
#: unless very soft (a velocity-100 snare is found down to a share of 0.1).
FROM_SILENCE = 0.15
#: A mix's second onset function: the SuperFlux of the bands above HIGH_HZ (a hi-hat, a
#: cymbal), picked with a short pre-max window, HIGH_GAP_S after the full-band onset at the
#: least, at HIGH_DELTA and HIGH_FLOOR times the full-band thresholds; its onsets report only
#: HIGH_CLASSES.
HIGH_HZ = 8800.0
HIGH_PRE_MAX_S = 0.006
HIGH_GAP_S = 0.006
HIGH_DELTA = 0.1
HIGH_FLOOR = 0.1
HIGH_CLOSE_SHARE = 0.0  # no share of the last onset needed: a hat after a snare is weaker
HIGH_CLASSES = frozenset(CLASSES.index(c) for c in ("hihat_closed", "hihat_open", "crash", "ride"))
#: Multi-mic crosstalk: an onset is the channel's own drum when crosstalk does not explain
#: OWN_SHARE of its rise, or when what is left is OWN_LEVEL of its drum's full-strength level
#: at the least (velocity 18: a soft hi-hat struck with a loud snare is mostly snare).
OWN_SHARE = 0.4
OWN_LEVEL = 0.02
#: A cymbal's or hi-hat's microphone: its onset function is the SuperFlux of the bands above
#: MIC_HIGH_HZ alone (the drums it hears through the air are lower), at MIC_HIGH_SCALE of the
#: profile's thresholds (fewer bands, smaller sums); other channels at MIC_SCALE of them.
MIC_HIGH_HZ = 3500.0
MIC_HIGH_SCALE = 0.2
MIC_SCALE = 1.0
#: A ringing cymbal's microphone (the classes of RING): an onset there is picked at the piece's
#: ``floor`` and ``delta`` shares of the thresholds (a stroke on a still-ringing cymbal rises
#: little above the ring) and kept only when the level above MIC_HIGH_HZ (the mean log band)
#: in the ``lookahead`` frames after it tops its mean over the RING_BEFORE frames up to two
#: before it by the piece's ``jump``: a stroke, however soft, lifts the ring it lands on; the
#: ring's own wobble rises and falls back. The crash's wobble (a loud cymbal's) swings further
#: than a soft ride stroke lifts, and a crash is seldom struck softly: a larger jump.
RING_BEFORE = 7


@dataclass(frozen=True)
class Ring:
    """How a ringing cymbal's channel picks its strokes (see :data:`RING`)."""

    floor: float  # share of the onset floor
    delta: float  # share of the onset delta above the moving mean
    jump: float  # the level lift (mean log band) a stroke must give


RING: dict[int, Ring] = {
    CLASSES.index("ride"): Ring(floor=0.5, delta=0.5, jump=0.06),
    CLASSES.index("crash"): Ring(floor=0.5, delta=1.0, jump=0.1),
}
#: Steady noise (see the module docstring): the level lift (mean log band) a hi-hat's
#: microphone's onset and a mix's high-band onset must give; the lift (log10 of the 21 ms band
#: spectrum's total) a ringing cymbal's onset must also give.
HIGH_LIFT = 0.1
RING_BAND_LIFT = 0.02
#: A second look after crosstalk (one microphone per drum): when a channel's onset is dropped
#: as another drum's crosstalk, for RESCUE_S after it the channel's own drum may still be
#: found: a frame that tops the frames it waits for, where what is left after crosstalk is
#: RESCUE_SHARE of the rise at least and RESCUE_LEVEL of the drum's full-strength level.
RESCUE_S = 0.012
RESCUE_SHARE = 0.5
RESCUE_LEVEL = 0.05
BATCH = 2048  # frames per FFT batch (bounds memory for a long file)
_EPS = 1e-9


def tail_samples(lookahead: int = 8) -> int:
    """Silence :func:`detect` appends so the hits of the last frames are decided."""
    return (lookahead + 1) * HOP


def activations(feature: np.ndarray, profile: AudioProfile) -> np.ndarray:
    """Per-class activation of one band feature: KL-NMF with the profile's fixed bases (each
    template sums to 1, so an activation is the band-sum of what its class added)."""
    w = profile.templates.T  # (N_BANDS, K)
    total = float(feature.sum())
    if total <= 0:
        return np.zeros(len(CLASSES))
    k = w.shape[1]
    h = np.full(k, total / k)
    for _ in range(NMF_ITERATIONS):
        h *= w.T @ (feature / (w @ h + _EPS))
    out = np.zeros(len(CLASSES))
    np.add.at(out, profile.template_class, h)
    return out


def velocity_of(level: float, ref: float) -> int:
    if ref <= 0:
        ref = level if level > 0 else 1.0
    return int(np.clip(round(127.0 * np.sqrt(max(level, 0.0) / ref)), 1, 127))


class _Peaks:
    """One onset function's recent values and the online peak picking on them."""

    def __init__(
        self, sr: int, lookahead: int, pre_max_s: float, combine_s: float, close_share: float
    ) -> None:
        self.sr = sr
        self.lookahead = lookahead
        self.pre_max = max(1, int(pre_max_s * sr / HOP))
        self.combine = int(combine_s * sr / HOP)
        self.pre_avg = int(PRE_AVG_S * sr / HOP)
        keep = max(self.pre_avg, self.pre_max) + lookahead + 2
        self.values: deque[float] = deque([0.0] * keep, maxlen=keep)
        self.last_onset = -(10**9)
        self.last_value = 0.0
        self.close = math.ceil(SAME_DRUM_S * sr / HOP)
        self.close_share = close_share

    def is_onset(self, frame: int, delta: float, floor: float) -> bool:
        """Whether frame ``frame`` (``lookahead`` frames before the newest) is an onset."""
        value = self.values[-1 - self.lookahead]
        if value < floor or frame - self.last_onset < self.combine:
            return False  # (most frames: decided before the window is copied)
        f = list(self.values)
        p = len(f) - 1 - self.lookahead
        if frame - self.last_onset < self.close and value < self.close_share * self.last_value:
            return False
        if value <= max(f[p - self.pre_max : p]) or value < max(f[p + 1 :]):
            return False
        return value >= float(np.mean(f[p - self.pre_avg : p + 1])) + delta

    def tops_ahead(self) -> bool:
        """Whether the frame being decided is not below the ``lookahead`` frames after it."""
        f = list(self.values)
        return f[-1 - self.lookahead] >= max(f[len(f) - self.lookahead :], default=0.0)

    def mark(self, frame: int) -> None:
        """Frame ``frame`` was taken as an onset."""
        self.last_onset = frame
        self.last_value = self.values[len(self.values) - 1 - self.lookahead]


class _Channel:
    """One channel's frames, its onset function(s) and the band spectra a rise is read from.

    ``high``: a mix also picks peaks on a second onset function, the SuperFlux of the bands
    above :data:`HIGH_HZ` alone (see :class:`OnlineDetector`)."""

    def __init__(
        self, sr: int, lookahead: int, mode: str, high: bool = False, main_hz: float = 0.0
    ) -> None:
        self.sr = sr
        #: the main onset function's lowest band (a hi-hat's microphone: MIC_HIGH_HZ)
        self.main_from = int(np.searchsorted(flux_edges(sr), main_hz * FLUX_SIZE / sr))
        self.main = _Peaks(sr, lookahead, PRE_MAX_S[mode], COMBINE_S[mode], CLOSE_SHARE)
        self.high = (
            _Peaks(sr, lookahead, HIGH_PRE_MAX_S, HIGH_GAP_S, HIGH_CLOSE_SHARE) if high else None
        )
        self.high_from = int(np.searchsorted(flux_edges(sr), HIGH_HZ * FLUX_SIZE / sr))
        self.bands: deque[np.ndarray] = deque(
            [np.zeros(N_BANDS)] * (BEFORE + lookahead + 1), maxlen=BEFORE + lookahead + 1
        )
        self.logs: deque[np.ndarray] = deque([np.zeros(FLUX_BANDS)] * MU, maxlen=MU)
        keep = RING_BEFORE + BEFORE + lookahead
        #: the mean log band above main_from of the last frames (a ringing cymbal's level)
        self.level: deque[float] = deque([0.0] * keep, maxlen=keep)
        #: the mean log band above HIGH_HZ (a mix's high-band function's level)
        self.level_high: deque[float] = deque([0.0] * keep, maxlen=keep)
        self.crosstalk_at = -(10**9)

    def frames(
        self, signal: np.ndarray, ends: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Onset function, high-band onset function, band spectra, level (the mean log band
        from ``main_from``) and high-band level of the frames ending at ``ends``."""
        logs = log_flux_spectra(frames_at(signal, ends, FLUX_SIZE), self.sr)
        before = np.concatenate([np.array(self.logs), logs])[: len(logs)]
        m = self.main_from
        # the reference frame's oldest hop all zeros: a rise out of digital silence
        oldest = ends[:, None] - MU * HOP - FLUX_SIZE + np.arange(HOP)[None, :]
        scale = np.where(np.any(signal[oldest] != 0.0, axis=1), 1.0, FROM_SILENCE)
        flux = scale * superflux(logs[:, m:], before[:, m:])
        k = self.high_from
        high, level_high = flux, flux
        if self.high is not None:
            high = scale * superflux(logs[:, k:], before[:, k:])
            level_high = logs[:, k:].mean(axis=1)
        for row in logs[-MU:]:
            self.logs.append(row)
        level = logs[:, m:].mean(axis=1)
        return flux, high, bands(frames_at(signal, ends, CLASS_SIZE), self.sr), level, level_high

    def push(
        self, flux: float, high: float, band: np.ndarray, level: float, level_high: float
    ) -> None:
        self.main.values.append(flux)
        self.level.append(level)
        if self.high is not None:
            self.high.values.append(high)
            self.level_high.append(level_high)
        self.bands.append(band)

    def rise(self) -> np.ndarray:
        """The band rise of the frame being decided: ``lookahead`` frames after it minus
        :data:`BEFORE` frames before it."""
        out: np.ndarray = np.maximum(self.bands[-1] - self.bands[0], 0.0)
        return out

    def lifted(self, jump: float, high: bool = False) -> bool:
        """Whether the level (``high``: the high-band level) after the frame being decided tops
        its level before by ``jump`` (the frame being decided is ``lookahead`` frames before
        the newest)."""
        v = list(self.level_high if high else self.level)
        after = v[len(v) - max(1, self.main.lookahead) :]
        before = v[:RING_BEFORE]
        return float(np.mean(after)) - float(np.mean(before)) >= jump

    def band_lifted(self, jump: float) -> bool:
        """Whether the band spectrum's total rose by ``jump`` (log10) from :data:`BEFORE`
        frames before the frame being decided to ``lookahead`` frames after it."""
        after, before = float(self.bands[-1].sum()), float(self.bands[0].sum())
        return math.log10(after + _EPS) - math.log10(before + _EPS) >= jump

    def ringing(self) -> bool:
        """Whether no frame of the :data:`RING_BEFORE` before the frame being decided was
        digital silence (a level of exactly 0: a stream's or a file's start)."""
        return min(list(self.level)[:RING_BEFORE]) > 0.0


class OnlineDetector:
    """Hits from a live stream, block by block (see the module docstring).

    ``channels``: ``None`` for a mix (every class from one signal; a multi-channel block is
    averaged to mono), or the class code of each input channel (one microphone per drum).
    ``one_drum``: a mix known to hold one drum at a time (learning): the one-drum picking
    windows (see :data:`PRE_MAX_S`).
    """

    def __init__(
        self,
        profile: AudioProfile,
        sr: int,
        channels: Sequence[int] | None = None,
        one_drum: bool = False,
        model: HitModel | None = None,
    ):
        self.profile = profile
        self.sr = sr
        self.one_drum = one_drum
        self.channel_class = None if channels is None else list(channels)
        #: A mix's classifier: the learned model (:mod:`.model`) or, when None, the profile's
        #: templates. With a model the onsets are picked at its thresholds.
        self.model = model
        if model is not None and channels is None and profile.settings.lookahead != 2:
            raise ValueError("the acoustic model needs a lookahead of 2 frames")
        #: When a list: the band rise of every mix-mode onset is appended (for learning).
        self.features: list[np.ndarray] | None = None
        #: When a list: every mix-mode onset candidate is appended as (time_s, model
        #: features, band rise total) (for training the model).
        self.candidates: list[tuple[float, np.ndarray, float]] | None = None
        self.reset()

    @property
    def latency_s(self) -> float:
        """Decision delay after the frame whose window first holds the attack's peak."""
        return self.profile.settings.lookahead * HOP / self.sr

    def reset(self) -> None:
        n = 1 if self.channel_class is None else len(self.channel_class)
        mode = "one_drum" if self.one_drum else "mix" if self.channel_class is None else "mics"
        look = self.profile.settings.lookahead
        if self.channel_class is None:
            self._chans = [_Channel(self.sr, look, mode, high=mode == "mix")]
        else:
            self._chans = [
                _Channel(self.sr, look, mode, main_hz=MIC_HIGH_HZ * (c in HIGH_CLASSES))
                for c in self.channel_class
            ]
        #: onset thresholds of each channel, a share of the profile's (MIC_HIGH_SCALE)
        self._scale = [MIC_SCALE if ch.main_from == 0 else MIC_HIGH_SCALE for ch in self._chans]
        self._last_hit = np.full(len(CLASSES), -(10**9))  # frame of each drum's last hit
        self._history = np.zeros((CLASS_SIZE, n), np.float64)  # the last samples seen
        self._pending = 0  # samples after the last frame end, at the end of _history
        self._frame = -1  # index of the newest frame
        self.frames_seen = 0
        #: the model's running mean of this recording's onset spectra (see :mod:`.model`)
        self._norm = None if self.model is None else RecordingNorm(self.model.prior)

    def process(self, block: np.ndarray) -> np.ndarray:
        """Hits decided by the samples of ``block`` (HIT_DTYPE, sorted by time)."""
        data = np.asarray(block, np.float64)
        if data.ndim == 1:
            data = data[:, None]
        if self.channel_class is None and data.shape[1] != 1:
            data = data.mean(axis=1, keepdims=True)
        elif self.channel_class is not None and data.shape[1] != len(self.channel_class):
            raise ValueError(
                f"block has {data.shape[1]} channels, expected {len(self.channel_class)}"
            )
        signal = np.concatenate([self._history, data])
        start = self._history.shape[0] - self._pending  # first new sample after a frame end
        n_frames = (self._pending + data.shape[0]) // HOP
        out: list[tuple[float, int, int, float, int]] = []
        for b0 in range(0, n_frames, BATCH):
            ends = start + HOP * np.arange(b0 + 1, min(n_frames, b0 + BATCH) + 1)
            per_chan = [ch.frames(signal[:, c], ends) for c, ch in enumerate(self._chans)]
            for i in range(len(ends)):
                self._frame += 1
                for c, ch in enumerate(self._chans):
                    flux, high, band, level, level_high = per_chan[c]
                    ch.push(
                        float(flux[i]),
                        float(high[i]),
                        band[i],
                        float(level[i]),
                        float(level_high[i]),
                    )
                out.extend(self._decide())
        self.frames_seen = self._frame + 1
        self._pending = (self._pending + data.shape[0]) % HOP
        self._history = signal[-CLASS_SIZE:]
        return np.array(out, HIT_DTYPE)

    def _decide(self) -> list[tuple[float, int, int, float, int]]:
        s = self.profile.settings
        p = self._frame - s.lookahead
        time_s = (p + 1) * HOP / self.sr - s.offset_ms / 1000.0
        hits: list[tuple[float, int, int, float, int]] = []
        if self.channel_class is None:
            return self._decide_mix(p, time_s)
        all_rises = [ch.rise() for ch in self._chans]
        rescue = math.ceil(RESCUE_S * self.sr / HOP)
        for c, ch in enumerate(self._chans):
            cls = self.channel_class[c]
            ring = RING.get(cls)
            if ring is not None and not ch.ringing():
                ring = None  # out of digital silence: the plain thresholds
            delta = self._scale[c] * s.delta * (ring.delta if ring else 1.0)
            floor = self._scale[c] * s.floor * (ring.floor if ring else 1.0)
            onset = ch.main.is_onset(p, delta, floor)
            second = not onset and p - ch.crosstalk_at <= rescue and ch.main.tops_ahead()
            if not onset and not second:
                continue
            if ring and not (ch.lifted(ring.jump) and ch.band_lifted(RING_BAND_LIFT)):
                continue  # the ring's wobble: no lasting rise of its level
            if not ring and cls in HIGH_CLASSES and not ch.lifted(HIGH_LIFT):
                continue  # a steady noise's jitter
            rise = all_rises[c]
            level = float(rise.sum())
            others = [all_rises[d] for d in range(len(all_rises)) if d != c]
            leaked = s.leak * np.max(others, axis=0) if others else np.zeros_like(rise)
            own = float(np.maximum(rise - leaked, 0.0).sum())
            full = self.profile.levels[cls]
            if level < s.min_level:
                continue
            if second:
                if own < max(RESCUE_SHARE * level, RESCUE_LEVEL * full):
                    continue  # still mostly the other drum's crosstalk
                level = own  # the velocity of what is left
            elif own < OWN_SHARE * level and not own >= OWN_LEVEL * full > 0:
                ch.crosstalk_at = p  # crosstalk: most of this rise is another channel's
                continue
            ch.main.mark(p)
            ch.crosstalk_at = -(10**9)
            hits.append((time_s, cls, velocity_of(level, full), level, c))
        return hits

    def _decide_mix(self, p: int, time_s: float) -> list[tuple[float, int, int, float, int]]:
        s = self.profile.settings
        ch = self._chans[0]
        hits: list[tuple[float, int, int, float, int]] = []
        if self.model is not None:
            delta, floor = self.model.delta, self.model.floor
        elif self.candidates is not None:  # training: the model's default picking
            delta, floor = PICK_DELTA, PICK_FLOOR
        else:
            delta, floor = s.delta, s.floor
        if ch.main.is_onset(p, delta, floor):
            allowed = None
        elif (
            ch.high is not None
            and p - ch.main.last_onset >= ch.high.combine
            and ch.high.is_onset(p, HIGH_DELTA * delta, HIGH_FLOOR * floor)
            and ch.lifted(HIGH_LIFT, high=True)  # not a steady noise's jitter
        ):
            allowed = HIGH_CLASSES
        else:
            return hits
        rise = ch.rise()
        if self.features is not None:
            self.features.append(rise)
        if self.model is not None or self.candidates is not None:
            return self._decide_learned(p, time_s, rise, allowed)
        act = activations(rise, self.profile)
        if allowed is not None:  # the strongest high drum, whatever a ringing drum adds
            act[[c for c in range(len(CLASSES)) if c not in allowed]] = 0.0
        top = float(act.max())
        if top < s.min_level:
            return hits
        if allowed is None:
            ch.main.mark(p)
        if ch.high is not None:
            ch.high.mark(p)
        levels = self.profile.levels
        need = np.where(levels > 0, s.poly * levels, s.poly * top)
        quietest = np.where(levels > 0, QUIETEST * levels, 0.0)  # a hit at velocity ~9
        found = (act >= np.maximum(need, s.min_level)) | ((act == top) & (act >= quietest))
        recent = p - self._last_hit < math.ceil(SAME_DRUM_S * self.sr / HOP)
        for cls in np.flatnonzero(found & ~recent).tolist():
            if allowed is not None and cls not in allowed:
                continue
            self._last_hit[cls] = p
            level = float(act[cls])
            hits.append((time_s, cls, velocity_of(level, self.profile.levels[cls]), level, 0))
        return hits

    def _decide_learned(
        self, p: int, time_s: float, rise: np.ndarray, allowed: frozenset[int] | None
    ) -> list[tuple[float, int, int, float, int]]:
        """A candidate onset classified by the model (every candidate is an onset for the
        picking, whatever the model says: training saw them so)."""
        ch = self._chans[0]
        if allowed is None:
            ch.main.mark(p)
        if ch.high is not None:
            ch.high.mark(p)
        feature = hit_features(np.array(ch.bands), allowed is not None)
        level = float(rise.sum())
        if self.candidates is not None:
            self.candidates.append((time_s, feature, level))
        if self.model is None or self._norm is None:
            return []
        prob = self.model.probabilities(model_input(feature, self._norm.mean))
        self._norm.update(feature)
        if allowed is not None:
            prob[[c for c in range(len(CLASSES)) if c not in allowed]] = 0.0
        recent = p - self._last_hit < math.ceil(SAME_DRUM_S * self.sr / HOP)
        hits: list[tuple[float, int, int, float, int]] = []
        for cls in np.flatnonzero((prob >= self.model.thresholds) & ~recent).tolist():
            self._last_hit[cls] = p
            ref = float(self.model.ref_level[cls])
            hits.append((time_s, cls, velocity_of(level, ref), level, 0))
        return hits


def detect(
    audio: np.ndarray,
    sr: int,
    profile: AudioProfile,
    channels: Sequence[int] | None = None,
    model: HitModel | None = None,
) -> np.ndarray:
    """The offline twin: every hit of ``audio`` ((n,) or (n, channels) float); a mix is
    classified by ``model`` when given (else by the profile's templates)."""
    det = OnlineDetector(profile, sr, channels, model=model)
    data = np.asarray(audio, np.float64)
    pad = np.zeros((tail_samples(profile.settings.lookahead), *data.shape[1:]))
    return det.process(np.concatenate([data, pad]))
