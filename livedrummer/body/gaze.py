"""Where the drummer looks: the gaze follows the piece being struck, smoothed and limited.

Why this shape. Looking at every hit in turn makes a head that twitches between hi-hat and
snare at every sixteenth. A player's gaze settles where the playing is and moves when it
moves: here each hand onset pulls the gaze towards its target (azimuth and elevation from
the head) with weight ``1 - exp(-gap / smooth_s)``, ``gap`` being the time since the previous
onset; so a run of alternating hits holds the gaze between them, and a hit after a rest (a
crash after a fill, a floor tom) takes it nearly all the way. The gaze is keyed
``look_ahead_s`` before each onset (the eyes arrive first), kept within ``yaw_max_deg`` and
``pitch_deg`` of straight ahead, and turns no faster than ``speed_deg_s``. The pull is a
causal filter over the onsets, so the live synth (re-animating a window of recent notes)
draws the same gaze as the whole performance once its window covers a few onsets.

The head takes ``look_fraction`` of the gaze (the torso module's keys); the eyes make up the
rest, up to ``eye_max_deg``: :func:`eye_angles` reads them back from a pose's head rotation
alone (the fraction is fixed), so whoever draws a pose record, offline or live, turns the eyes
the same way without any new field in the record.

Limits: one gaze for both hands (the latest onset of either hand leads); no saccades or
fixational jitter; the eyes' vertical share is measured against the neutral seated head.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body import quat


@dataclass(frozen=True, slots=True)
class GazeParams:
    smooth_s: float = 0.12  # an onset this long after the previous one pulls the gaze 63 %
    speed_deg_s: float = 400.0  # the gaze turns no faster
    yaw_max_deg: float = 75.0  # left or right of straight ahead
    pitch_deg: tuple[float, float] = (-65.0, 10.0)  # down .. up
    eye_max_deg: float = 25.0  # the eyes turn at most this far in the head


def azimuth(points: np.ndarray) -> np.ndarray:
    """Turn about +z (radians) that faces a point from the seat (positive = to the left)."""
    out: np.ndarray = -np.arctan2(points[..., 0], points[..., 1])
    return out


def elevation(points: np.ndarray) -> np.ndarray:
    """Angle (radians) above the horizontal of directions ``points``."""
    out: np.ndarray = np.arctan2(points[..., 2], np.hypot(points[..., 0], points[..., 1]))
    return out


def gaze_keys(
    onset_s: np.ndarray, rel: np.ndarray, params: GazeParams
) -> tuple[np.ndarray, np.ndarray]:
    """The whole gaze's (yaw, pitch) in radians at each onset, from the targets' directions
    ``rel`` (N, 3) seen from the head (see the module docstring)."""
    n = onset_s.size
    if n == 0:
        return np.zeros(0), np.zeros(0)
    lo, hi = np.radians(params.pitch_deg)
    lim = np.radians(params.yaw_max_deg)
    raw_yaw = np.clip(azimuth(rel), -lim, lim)
    raw_pitch = np.clip(elevation(rel), lo, hi)
    pull = 1.0 - np.exp(-np.diff(onset_s) / params.smooth_s)
    cap = np.radians(params.speed_deg_s) * np.diff(onset_s)
    yaw, pitch = np.empty(n), np.empty(n)
    yaw[0], pitch[0] = raw_yaw[0], raw_pitch[0]
    for k in range(1, n):
        for out, raw in ((yaw, raw_yaw), (pitch, raw_pitch)):
            step = pull[k - 1] * (raw[k] - out[k - 1])
            out[k] = out[k - 1] + float(np.clip(step, -cap[k - 1], cap[k - 1]))
    return yaw, pitch


#: Forward of the head in its own frame (the body's rest pose faces +y).
FORWARD = np.array([0.0, 1.0, 0.0])


def eye_angles(
    head_world_q: np.ndarray, look_fraction: float, neutral_pitch_rad: float, params: GazeParams
) -> tuple[np.ndarray, np.ndarray]:
    """The eyes' (yaw, pitch) in the head, radians, from the head's world rotations (T, 4):
    the share of the gaze the head leaves to them (see the module docstring)."""
    fwd = quat.rotate(head_world_q, np.broadcast_to(FORWARD, (*head_world_q.shape[:-1], 3)))
    share = (1.0 - look_fraction) / look_fraction
    lim = np.radians(params.eye_max_deg)
    yaw = np.clip(share * azimuth(fwd), -lim, lim)
    pitch = np.clip(share * (elevation(fwd) - neutral_pitch_rad), -lim, lim)
    return yaw, pitch


def gaze_direction(
    head_world_q: np.ndarray, look_fraction: float, neutral_pitch_rad: float, params: GazeParams
) -> np.ndarray:
    """Unit gaze directions (T, 3): the head's forward turned by :func:`eye_angles`."""
    fwd = quat.rotate(head_world_q, np.broadcast_to(FORWARD, (*head_world_q.shape[:-1], 3)))
    yaw, pitch = eye_angles(head_world_q, look_fraction, neutral_pitch_rad, params)
    az = azimuth(fwd) + yaw
    el = elevation(fwd) + pitch
    return np.stack([-np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)], axis=-1)


def neutral_head_pitch(lean_deg: float) -> float:
    """Elevation (radians) of the head's forward with no look and no bob: the seated torso's
    lean, its chest's 0.3 of it back and the neck's 1.3 of it (the torso's rest pose)."""
    lean = np.radians(lean_deg)
    x = np.array([1.0, 0.0, 0.0])
    q = quat.mul(
        quat.from_axis_angle(x, np.array([-lean])),
        quat.mul(
            quat.from_axis_angle(x, np.array([0.3 * lean])),
            quat.from_axis_angle(x, np.array([1.3 * lean])),
        ),
    )
    return float(elevation(quat.rotate(q, FORWARD[None]))[0])
