"""Secondary motion: torso twist and sway, head bob with SMED's cofactors, head look-at.

Computed before the arms (as in SMED) because the torso carries the shoulders: the arm IK
is solved at each onset with the torso where it will be at that instant. Every component is
a function of time built from keys:

* **Twist** (lower back and chest, about +z): at each hand onset the drummer turns a fraction
  of the way towards the struck piece; consecutive keys are clipped so the angular velocity
  never exceeds ``twist_cap_deg_s``; linear between keys, so the cap holds everywhere.
* **Sway** (lower back, forward pitch): down on every beat, upright at mid-beat, CTB between.
* **Head bob** (neck pitch): same rhythm, amplitude scaled per beat by SMED's bobbing factor,
  the product of a *velocity cofactor* (mean velocity of kick, snare, tom and crash onsets
  within the 25 ms strike range, plus 10 % per such onset) and a *density cofactor* (rests
  between the strike range and the mid-beat, each sub-interval weighted ``w_i / (1 + i c)``
  with i counted from 0 next to the beat, so an empty side gives exactly 1; the larger side
  wins).
* **Look-at** (head yaw and pitch): keyed slightly before each hand onset, ``look_fraction``
  of the gaze towards the struck target, smoothed and limited (:mod:`~livedrummer.body.gaze`:
  a run of alternating hits holds the gaze between them; the eyes turn the rest).
* **Style** (:class:`TorsoStyle`, from the expression): sway and bob keyed on a grid of
  ``frequency`` times the beats (0.5: every other beat, 2: on every half beat, interpolated
  through the beats' own times, so it follows a changing tempo); a sideways sway (lower
  back roll, about the forward axis) to one side on one beat of its grid and to the other
  on the next; a constant sideways head tilt.

Limits: the pelvis stays still on the throne; no breathing; one gaze for both hands.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from livedrummer.body import quat, spline
from livedrummer.body.gaze import GazeParams, gaze_keys

X = np.array([1.0, 0.0, 0.0])
Y = np.array([0.0, 1.0, 0.0])
Z = np.array([0.0, 0.0, 1.0])

#: Instrument kinds whose onsets count for the velocity cofactor (not ride or hi-hat).
BOB_KINDS = frozenset({"kick", "snare", "tom", "crash", "splash", "china"})


@dataclass(frozen=True, slots=True)
class SecondaryParams:
    lean_deg: float = 10.0
    twist_cap_deg_s: float = 150.0
    twist_max_deg: float = 35.0
    strike_range_s: float = 0.025
    density_c: float = 1.0
    look_ahead_s: float = 0.12
    look_fraction: float = 0.6  # the head's share of the gaze; the eyes turn the rest
    gaze: GazeParams = field(default_factory=GazeParams)  # smoothing and limits


@dataclass(frozen=True, slots=True)
class TorsoStyle:
    """The expression's share of the torso (see the module docstring)."""

    back_frequency: float = 1.0  # sways per beat
    head_frequency: float = 1.0  # bobs per beat
    side_sway_rad: float = 0.0
    head_tilt_rad: float = 0.0


def beat_grid(beats: np.ndarray, per_beat: float) -> np.ndarray:
    """``per_beat`` keys per beat, placed through the beats' own times (linear in between)."""
    if per_beat == 1.0 or beats.size < 2:
        return beats
    index = np.arange(beats.size, dtype=np.float64)
    k = np.arange(0.0, (beats.size - 1) * per_beat + 1e-9) / per_beat
    out: np.ndarray = np.interp(k, index, beats)
    return out


def rate_limited(times: np.ndarray, goal: np.ndarray, cap_per_s: float) -> np.ndarray:
    """Keys following ``goal`` but moving at most ``cap_per_s`` between consecutive keys
    (the first key is reached: the drummer sits facing the first piece played)."""
    out = np.empty_like(goal)
    value, last = (float(goal[0]), float(times[0])) if times.size else (0.0, 0.0)
    for k in range(goal.size):
        step = cap_per_s * (times[k] - last)
        value = min(max(goal[k], value - step), value + step)
        out[k] = value
        last = times[k]
    return out


def velocity_cofactor(
    beats: np.ndarray, onset_s: np.ndarray, velocity: np.ndarray, strike_range_s: float
) -> np.ndarray:
    """Per beat: mean velocity (0..1) of the onsets within the strike range, +10 % each."""
    lo = np.searchsorted(onset_s, beats - strike_range_s, side="left")
    hi = np.searchsorted(onset_s, beats + strike_range_s, side="right")
    csum = np.concatenate([[0.0], np.cumsum(velocity)])
    n = hi - lo
    mean = np.where(n > 0, (csum[hi] - csum[lo]) / np.maximum(n, 1), 0.0)
    out: np.ndarray = mean * (1.0 + 0.1 * n)
    return out


def density_side(edges_from_beat: np.ndarray, w: float, c: float) -> float:
    """Density cofactor of one side: ``edges_from_beat`` are the onset distances (s) from the
    strike-range edge, inside an interval of length ``w``."""
    if w <= 0:
        return 1.0
    cuts = np.concatenate([[0.0], np.sort(edges_from_beat), [w]])
    sub = np.diff(cuts)
    i = np.arange(sub.size)
    return float(np.sum(sub / (1.0 + i * c)) / w)


def density_cofactor(
    beats: np.ndarray, beat_len: np.ndarray, onset_s: np.ndarray, strike_range_s: float, c: float
) -> np.ndarray:
    """Per beat: the larger of the two sides' density cofactors (see the module docstring)."""
    out = np.empty(beats.size)
    for k, (b, length) in enumerate(zip(beats, beat_len, strict=True)):
        w = max(0.5 * length - strike_range_s, 0.0)
        after = onset_s[(onset_s > b + strike_range_s) & (onset_s < b + strike_range_s + w)]
        before = onset_s[(onset_s < b - strike_range_s) & (onset_s > b - strike_range_s - w)]
        out[k] = max(
            density_side(after - (b + strike_range_s), w, c),
            density_side((b - strike_range_s) - before, w, c),
        )
    return out


def _beat_keys(beats: np.ndarray, amp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keys down on each beat (value amp) and back to 0 at each mid-beat."""
    if beats.size == 0:
        return np.array([0.0]), np.array([0.0])
    length = np.diff(beats, append=beats[-1] + (beats[-1] - beats[-2] if beats.size > 1 else 0.5))
    t = np.empty(2 * beats.size)
    v = np.zeros(2 * beats.size)
    t[0::2] = beats
    t[1::2] = beats + 0.5 * length
    v[0::2] = amp
    return t, v


@dataclass(frozen=True)
class Torso:
    """Key curves of the torso and head; :meth:`locals` samples them."""

    lean_rad: float
    twist_t: np.ndarray
    twist_rad: np.ndarray
    sway_t: np.ndarray
    sway_rad: np.ndarray
    bob_t: np.ndarray
    bob_rad: np.ndarray
    look_t: np.ndarray
    look_yaw: np.ndarray
    look_pitch: np.ndarray
    roll_t: np.ndarray = field(default_factory=lambda: np.zeros(1))  # sideways sway keys
    roll_rad: np.ndarray = field(default_factory=lambda: np.zeros(1))
    tilt_rad: float = 0.0  # sideways head tilt

    def roll(self, times: np.ndarray) -> np.ndarray:
        if not self.roll_rad.any():
            return np.zeros_like(times)
        return spline.evaluate(self.roll_t, self.roll_rad, times)

    def twist(self, times: np.ndarray) -> np.ndarray:
        if self.twist_t.size == 0:
            return np.zeros_like(times)
        out: np.ndarray = np.interp(times, self.twist_t, self.twist_rad)
        return out

    def back(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (T, 4) of lower_back and chest only (what carries the arms)."""
        twist = self.twist(times)
        sway = spline.evaluate(self.sway_t, self.sway_rad, times)
        half = quat.from_axis_angle(Z, 0.5 * twist)
        turned = quat.mul(half, quat.from_axis_angle(Y, self.roll(times)))
        lower = quat.mul_x(turned, -(self.lean_rad + sway))
        chest = quat.mul_x(half, np.full_like(times, self.lean_rad * 0.3))
        return lower, chest

    def locals(self, times: np.ndarray) -> dict[str, np.ndarray]:
        """Local rotations (T, 4) of lower_back, chest, neck and head."""
        twist = self.twist(times)
        sway = spline.evaluate(self.sway_t, self.sway_rad, times)
        bob = spline.evaluate(self.bob_t, self.bob_rad, times)
        if self.look_t.size:
            yaw = np.interp(times, self.look_t, self.look_yaw) - twist
            pitch = np.interp(times, self.look_t, self.look_pitch)
        else:
            yaw = pitch = np.zeros_like(times)
        # forward lean and sway tip +z towards +y: a negative turn about +x
        turned = quat.mul(
            quat.from_axis_angle(Z, 0.5 * twist), quat.from_axis_angle(Y, self.roll(times))
        )
        lower = quat.mul(turned, quat.from_axis_angle(X, -(self.lean_rad + sway)))
        chest = quat.mul(
            quat.from_axis_angle(Z, 0.5 * twist),
            quat.from_axis_angle(X, np.full_like(times, self.lean_rad * 0.3)),
        )
        neck = quat.from_axis_angle(X, -bob + self.lean_rad * 1.3)
        head = quat.mul(quat.from_axis_angle(Z, yaw), quat.from_axis_angle(X, -pitch))
        if self.tilt_rad:
            head = quat.mul(head, quat.from_axis_angle(Y, np.full_like(times, self.tilt_rad)))
        return {"lower_back": lower, "chest": chest, "neck": neck, "head": head}


def azimuth(points: np.ndarray) -> np.ndarray:
    """Turn about +z (radians) that faces a point from the seat (positive = to the left)."""
    out: np.ndarray = -np.arctan2(points[..., 0], points[..., 1])
    return out


def build_torso(
    params: SecondaryParams,
    twist_fraction: float,
    back_amp_rad: float,
    head_amp_rad: float,
    beats: np.ndarray,
    hand_s: np.ndarray,
    hand_targets: np.ndarray,
    head_m: np.ndarray,
    bob_s: np.ndarray,
    bob_velocity: np.ndarray,
    all_onset_s: np.ndarray,
    style: TorsoStyle | None = None,
) -> Torso:
    """Torso keys from the hands' onsets (sorted) and their targets, and the beat grid."""
    st = style or TorsoStyle()
    cap = np.radians(params.twist_cap_deg_s)
    lim = np.radians(params.twist_max_deg)
    goal = np.clip(twist_fraction * azimuth(hand_targets), -lim, lim)
    twist_rad = rate_limited(hand_s, goal, cap)
    back_beats = beat_grid(beats, st.back_frequency)
    sway_t, sway_v = _beat_keys(back_beats, np.full(back_beats.size, back_amp_rad))
    roll_t = back_beats if back_beats.size else np.zeros(1)
    roll_v = st.side_sway_rad * np.where(np.arange(roll_t.size) % 2 == 0, 1.0, -1.0)
    bob_beats = beat_grid(beats, st.head_frequency)
    length = np.diff(bob_beats, append=bob_beats[-1] + 0.5) if bob_beats.size else bob_beats
    factor = velocity_cofactor(bob_beats, bob_s, bob_velocity, params.strike_range_s)
    factor = factor * density_cofactor(
        bob_beats, length, all_onset_s, params.strike_range_s, params.density_c
    )
    bob_t, bob_v = _beat_keys(bob_beats, head_amp_rad * np.clip(factor, 0.0, 1.5))
    rel = hand_targets - head_m
    gaze_yaw, gaze_pitch = gaze_keys(hand_s, rel, params.gaze)
    return Torso(
        lean_rad=np.radians(params.lean_deg),
        twist_t=hand_s,
        twist_rad=twist_rad,
        sway_t=sway_t,
        sway_rad=sway_v,
        bob_t=bob_t,
        bob_rad=bob_v,
        look_t=hand_s - params.look_ahead_s,
        look_yaw=params.look_fraction * gaze_yaw,
        look_pitch=-params.look_fraction * gaze_pitch,  # the head's pitch is positive down
        roll_t=roll_t,
        roll_rad=roll_v,
        tilt_rad=st.head_tilt_rad,
    )
