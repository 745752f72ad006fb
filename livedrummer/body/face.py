"""The face: blinks at natural intervals, a reaction to accents and crashes, the eyes' look.

Why this shape. A face is drawn from pose records and nothing else (the wire format carries
no face): what a record holds is its time, the kit channels' hit highlight (``glow``: the
latest hit's velocity, decaying with a 0.15 s time constant, :mod:`~livedrummer.body.channels`)
and the head's rotation. The offline renderer and the live display, given the same records,
draw the same face; a render is reproducible.

* **Blinks** come from a seeded schedule fixed in absolute time: time is cut into blocks of
  :data:`BLOCK_S`, and each block's blinks are drawn from a generator seeded by (seed, block)
  alone, so the face at any instant needs no history and no window can disagree with
  another. Intervals are log-normal (median ``blink_median_s``, the spread of spontaneous
  blinking) clipped to ``blink_range_s``; a blink closes in ``close_s`` and opens in
  ``open_s`` (eyelids are faster closing than opening). A block's first blink keeps the
  least interval from the previous block's last; across a block's edge an interval can be
  up to the range's top plus its bottom (11.2 s).
* **Reactions** (:class:`Reactions`): ``happy`` on accents (any piece hit at velocity
  ``accent`` or more), ``surprised`` on crash-like cymbals (crash, splash, china) hit at
  ``crash`` or more, held ``react_hold_s`` and relaxed over ``react_release_s``. The glow of a
  single record cannot tell a loud hit a moment ago from a soft one now, so hits are seen
  where the glow *rises* between the records a drawer draws in order: a small state, the same
  for a render and the live display up to one frame's timing.
* **Look**: the eyes' share of the gaze (:func:`~livedrummer.body.gaze.eye_angles`) as
  ``look_left/right/up/down`` weights, 1 at the eyes' limit.

Names are ours (:data:`FACES`); :mod:`~livedrummer.avatar.faces` maps a VRM's own
expressions (0.x blend shape groups, 1.0 expressions) onto them, and the built-in character
has its own shapes. Limits: no blink at a crash (a startle would need the hit's exact time, which a
record does not tell apart from a loud one a frame later); one reaction at a time wins (the
stronger).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from livedrummer.body.gaze import GazeParams, eye_angles, neutral_head_pitch

FACES = ("blink", "happy", "surprised", "look_left", "look_right", "look_up", "look_down")
BLOCK_S = 60.0
GLOW_TAU_S = 0.15  # the highlight's time constant (ChannelParams.glow_tau_s)
CRASH_KINDS = frozenset({"crash", "splash", "china"})


@dataclass(frozen=True, slots=True)
class FaceParams:
    seed: int = 0
    blink_median_s: float = 3.5
    blink_sigma: float = 0.45  # of the interval's logarithm
    blink_range_s: tuple[float, float] = (1.2, 10.0)
    close_s: float = 0.06
    hold_s: float = 0.03
    open_s: float = 0.12
    accent: float = 0.85  # velocity (0..1) of a hit that makes the face light up
    crash: float = 0.55  # velocity of a crash hit that surprises it
    react_hold_s: float = 0.15  # a reaction holds this long after its hit
    react_release_s: float = 0.5  # then relaxes over this


@lru_cache(maxsize=256)
def _block(seed: int, block: int, params: FaceParams) -> np.ndarray:
    rng = np.random.default_rng([seed & 0xFFFFFFFF, block & 0xFFFFFFFF, 0xB11C])
    lo, hi = params.blink_range_s
    mean_n = int(BLOCK_S / lo) + 2
    gaps = np.clip(
        params.blink_median_s * np.exp(params.blink_sigma * rng.standard_normal(mean_n)), lo, hi
    )
    start = block * BLOCK_S + rng.uniform(0.0, lo)
    t = start + np.concatenate([[0.0], np.cumsum(gaps)])
    out: np.ndarray = t[t < (block + 1) * BLOCK_S]
    return out


def blink_times(t0: float, t1: float, params: FaceParams) -> np.ndarray:
    """Blink start times (s) in ``[t0, t1)``, the same whatever the window asked for."""
    lo = params.blink_range_s[0]
    first, last = int(np.floor(t0 / BLOCK_S)) - 1, int(np.floor(t1 / BLOCK_S))
    parts = []
    prev = -np.inf
    for b in range(first, last + 1):
        t = _block(params.seed, b, params)
        t = t[t >= prev + lo]  # the least interval across a block's edge
        if t.size:
            prev = float(t[-1])
        parts.append(t)
    allt = np.concatenate(parts)
    out: np.ndarray = allt[(allt >= t0) & (allt < t1)]
    return out


def blink_weight(times: np.ndarray, params: FaceParams) -> np.ndarray:
    """How closed the eyes are (0 open .. 1 shut) at ``times``."""
    times = np.asarray(times, dtype=np.float64)
    if times.size == 0:
        return np.zeros(0)
    span = params.close_s + params.hold_s + params.open_s
    starts = blink_times(float(times.min()) - span, float(times.max()) + 1e-9, params)
    if starts.size == 0:
        return np.zeros_like(times)
    i = np.searchsorted(starts, times, side="right") - 1
    since = np.where(i >= 0, times - starts[np.maximum(i, 0)], np.inf)
    closing = np.clip(since / params.close_s, 0.0, 1.0)
    opening = np.clip((since - params.close_s - params.hold_s) / params.open_s, 0.0, 1.0)
    w = np.where(since < params.close_s, closing, 1.0 - opening)
    out: np.ndarray = np.where(since < span, _ease(w), 0.0)
    return out


def _ease(x: np.ndarray) -> np.ndarray:
    out: np.ndarray = x * x * (3.0 - 2.0 * x)
    return out


class Reactions:
    """The face's reactions to hits, from the records of one drawer in time order (see the
    module docstring): :meth:`update` with each record's time and glow gives (happy,
    surprised). A hit is seen where a piece's glow rises above what its decay since the last
    record leaves; its velocity is the glow then, brought back to the middle of the interval.
    Time going backwards (a seek, a loop) starts afresh."""

    def __init__(self, crash_like: np.ndarray, params: FaceParams | None = None) -> None:
        self.crash_like = np.asarray(crash_like, dtype=bool)
        self.params = params or FaceParams()
        self.reset()

    def reset(self) -> None:
        self._t = -np.inf
        self._glow = np.zeros(self.crash_like.shape)
        self._hits: dict[str, tuple[float, float]] = {}  # reaction -> (time, peak weight)

    def update(self, time_s: float, glow: np.ndarray) -> tuple[float, float]:
        p = self.params
        g = np.clip(np.asarray(glow, dtype=np.float64), 0.0, 1.0)
        if time_s < self._t:
            self.reset()
        dt = time_s - self._t
        left = self._glow * (np.exp(-dt / GLOW_TAU_S) if np.isfinite(dt) else 0.0)
        rose = g > left + 0.02
        if rose.any():
            back = np.exp(0.5 * min(dt, 0.1) / GLOW_TAU_S) if np.isfinite(dt) else 1.0
            v = g * back
            kinds = (("happy", rose, p.accent), ("surprised", rose & self.crash_like, p.crash))
            for name, mask, threshold in kinds:
                if mask.any():
                    peak = float(
                        np.clip((v[mask].max() - 0.8 * threshold) / (0.2 * threshold), 0.0, 1.0)
                    )
                    if peak > 0.0 and peak >= self._weight(name, time_s):
                        self._hits[name] = (time_s, peak)
        self._t, self._glow = time_s, g
        happy, surprised = self._weight("happy", time_s), self._weight("surprised", time_s)
        return (0.0, surprised) if surprised >= happy else (happy, 0.0)

    def _weight(self, name: str, time_s: float) -> float:
        if name not in self._hits:
            return 0.0
        at, peak = self._hits[name]
        since = time_s - at - self.params.react_hold_s
        if since <= 0.0:
            return peak
        return peak * float(_ease(np.array(1.0 - min(since / self.params.react_release_s, 1.0))))


def face_weights(
    time_s: float,
    reactions: tuple[float, float],
    head_world_q: np.ndarray | None,
    look_fraction: float,
    neutral_pitch_rad: float,
    params: FaceParams,
    gaze: GazeParams | None = None,
) -> dict[str, float]:
    """Every weight of :data:`FACES` for one record: its blink, the (happy, surprised)
    :class:`Reactions` gave, and the eyes' look from the head's world rotation."""
    out = dict.fromkeys(FACES, 0.0)
    out["blink"] = float(blink_weight(np.array([time_s]), params)[0])
    out["happy"], out["surprised"] = reactions
    if head_world_q is not None:
        g = gaze or GazeParams()
        yaw, pitch = eye_angles(
            np.asarray(head_world_q, np.float64)[None], look_fraction, neutral_pitch_rad, g
        )
        lim = np.radians(g.eye_max_deg)
        out["look_left"] = float(np.clip(yaw[0] / lim, 0.0, 1.0))
        out["look_right"] = float(np.clip(-yaw[0] / lim, 0.0, 1.0))
        out["look_up"] = float(np.clip(pitch[0] / lim, 0.0, 1.0))
        out["look_down"] = float(np.clip(-pitch[0] / lim, 0.0, 1.0))
    return out


class FaceTrack:
    """One drawer's face: :meth:`weights` for each record it draws, in time order (the
    :class:`Reactions` state, the blink schedule and the eyes' look together)."""

    def __init__(
        self,
        crash_like: np.ndarray,
        params: FaceParams | None = None,
        look_fraction: float = 0.6,
        lean_deg: float = 10.0,
    ) -> None:
        self.params = params or FaceParams()
        self.reactions = Reactions(crash_like, self.params)
        self.look_fraction = look_fraction
        self.neutral_pitch_rad = neutral_head_pitch(lean_deg)

    def weights(
        self, time_s: float, glow: np.ndarray, head_world_q: np.ndarray | None
    ) -> dict[str, float]:
        glow = np.asarray(glow, dtype=np.float64)
        if glow.shape != self.reactions.crash_like.shape:  # a kit of another size: no crashes
            self.reactions = Reactions(np.zeros(glow.shape, dtype=bool), self.params)
        react = self.reactions.update(time_s, glow)
        return face_weights(
            time_s, react, head_world_q, self.look_fraction, self.neutral_pitch_rad, self.params
        )
