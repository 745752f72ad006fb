"""Kit animation channels: what moves on the kit itself, per piece, sampled like the body.

Three float channels per piece (so a kit of any size maps to fixed-width arrays):

* ``swing`` (radians): a cymbal's swing or a drum's shake after a hit, a kick beater's angle
  back from the head, a hi-hat footboard's angle. Hits follow the virtual-drummer paper's
  decaying sinusoid ``velocity * max_angle * eta**dt * sin(beta * dt)`` from the latest hit,
  with each piece's own amplitude and frequency (a cymbal's from its size, a drum's short shake:
  :func:`livedrummer.kit.behaviour.swing_of`); a new hit overrides the vibration in progress
  (the paper's rule, discontinuity included) and a choke (aftertouch grab) silences it until
  the next hit. Beater and footboard follow the foot's lift, the same curve that moves the
  foot, so foot and pedal cannot drift apart.
* ``lift`` (metres): the hi-hat top cymbal's height above closed, from the pedal controller.
* ``glow`` (0..1): SMED's skin highlight, the latest hit's velocity decaying exponentially.

Which piece does what is :data:`livedrummer.kit.behaviour.BEHAVIOURS`, not this module.
Limits: one wobble axis per piece; no stand motion.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from livedrummer.body.targets import HIHAT_MAX_LIFT_M, zone_target
from livedrummer.kit.behaviour import BEHAVIOURS, HitMotion, PedalMotion, swing_of
from livedrummer.kit.model import Piece
from livedrummer.kit.vocabulary import PieceKind, Zone

BEATER_LENGTH_M = 0.20
BEATER_MAX_RAD = BEHAVIOURS[PieceKind.KICK].pedal_swing_rad  # beater angle at full foot lift
PEDAL_MAX_RAD = BEHAVIOURS[PieceKind.HIHAT].pedal_swing_rad


@dataclass(frozen=True, slots=True)
class VibrationParams:
    max_angle_rad: float = 0.12
    eta: float = 0.08  # damping per second (0..1: smaller decays faster)
    beta: float = 2 * np.pi * 3.0  # rad/s
    glow_tau_s: float = 0.15


def piece_vibration(piece: Piece, p: VibrationParams) -> VibrationParams:
    """``p`` with the hit motion of ``piece`` (its kind and size; see the module docstring)."""
    s = swing_of(piece)
    return replace(p, max_angle_rad=s.max_angle_rad, eta=s.eta, beta=2 * np.pi * s.hz)


def vibration(
    times: np.ndarray,
    hit_s: np.ndarray,
    hit_velocity: np.ndarray,
    choke_s: np.ndarray,
    p: VibrationParams,
) -> np.ndarray:
    """Wobble angle at ``times`` from the latest hit (sorted arrays; velocity in 0..1)."""
    out = np.zeros_like(times, dtype=np.float64)
    if hit_s.size == 0:
        return out
    i = np.searchsorted(hit_s, times, side="right") - 1
    live = i >= 0
    k = np.maximum(i, 0)
    # Before the first hit dt is negative and eta**dt grows without bound (a first hit minutes
    # into a song overflows float64); those samples are masked, so they are evaluated at 0.
    dt = np.where(live, times - hit_s[k], 0.0)
    if choke_s.size:
        c = np.searchsorted(choke_s, times, side="right") - 1
        choked = (c >= 0) & (choke_s[np.maximum(c, 0)] >= hit_s[k])
        live &= ~choked
    angle = hit_velocity[k] * p.max_angle_rad * np.power(p.eta, dt) * np.sin(p.beta * dt)
    return np.where(live, angle, 0.0)


def glow(
    times: np.ndarray, hit_s: np.ndarray, hit_velocity: np.ndarray, tau_s: float
) -> np.ndarray:
    if hit_s.size == 0:
        return np.zeros_like(times, dtype=np.float64)
    i = np.searchsorted(hit_s, times, side="right") - 1
    k = np.maximum(i, 0)
    dt = np.where(i >= 0, times - hit_s[k], 0.0)  # no exp of a large positive before the first hit
    return np.where(i >= 0, hit_velocity[k] * np.exp(-dt / tau_s), 0.0)


def beater_tip(piece: Piece, angle: np.ndarray) -> np.ndarray:
    """Kick beater tip (..., 3) at ``angle`` back from the head; 0 is the contact point."""
    contact = zone_target(piece, Zone.HEAD).point
    n = piece.normal  # towards the drummer
    up = np.array([0.0, 0.0, 1.0])
    pivot = contact - BEATER_LENGTH_M * up
    a = np.asarray(angle, dtype=np.float64)[..., None]
    out: np.ndarray = pivot + BEATER_LENGTH_M * (np.cos(a) * up + np.sin(a) * n)
    return out


@dataclass(frozen=True)
class KitChannels:
    swing: np.ndarray  # (T, P)
    lift: np.ndarray  # (T, P)
    glow: np.ndarray  # (T, P)


def kit_channels(
    pieces: tuple[Piece, ...],
    times: np.ndarray,
    hit_s: list[np.ndarray],
    hit_velocity: list[np.ndarray],
    choke_s: list[np.ndarray],
    foot_lift: list[np.ndarray | None],
    openness: np.ndarray,
    p: VibrationParams | None = None,
) -> KitChannels:
    """Channels for every piece; per-piece lists hold that piece's hits and chokes (sorted),
    and the lift curve of the foot on its pedal (or None); ``p`` gives the glow's time constant,
    each piece's hit motion is its own (:func:`piece_vibration`)."""
    p = p or VibrationParams()
    t = times.size
    swing = np.zeros((t, len(pieces)))
    lift = np.zeros((t, len(pieces)))
    lum = np.zeros((t, len(pieces)))
    for k, piece in enumerate(pieces):
        lum[:, k] = glow(times, hit_s[k], hit_velocity[k], p.glow_tau_s)
        b = BEHAVIOURS[piece.kind]
        foot = foot_lift[k]
        if b.pedal is PedalMotion.HIHAT:
            lift[:, k] = HIHAT_MAX_LIFT_M * np.clip(openness, 0.0, 1.0)
            if foot is not None:
                swing[:, k] = b.pedal_swing_rad * foot
        elif b.pedal is PedalMotion.BEATER:
            if foot is not None:
                swing[:, k] = b.pedal_swing_rad * np.clip(foot, 0.0, None)
        elif b.hit is not HitMotion.NONE:
            own = piece_vibration(piece, p)
            swing[:, k] = vibration(times, hit_s[k], hit_velocity[k], choke_s[k], own)
    return KitChannels(swing, lift, lum)
