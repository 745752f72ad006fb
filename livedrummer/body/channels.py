"""Kit animation channels: what moves on the kit itself, per piece, sampled like the body.

Three float channels per piece (so a kit of any size maps to fixed-width arrays):

* ``swing`` (radians): a cymbal's wobble, a kick beater's angle back from the head, a
  hi-hat footboard's angle. Cymbals follow the virtual-drummer paper's decaying sinusoid
  ``velocity * max_angle * eta**dt * sin(beta * dt)`` from their latest hit; a new hit
  overrides the vibration in progress (the paper's rule, discontinuity included) and a choke
  (aftertouch grab) silences it until the next hit. Beater and footboard follow the foot's
  lift, the same curve that moves the foot, so foot and pedal cannot drift apart.
* ``lift`` (metres): the hi-hat top cymbal's height above closed, from the pedal controller.
* ``glow`` (0..1): SMED's skin highlight, the latest hit's velocity decaying exponentially.

Limits: one wobble axis per cymbal; no shell or stand motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body.targets import HIHAT_MAX_LIFT_M, zone_target
from livedrummer.kit.model import Piece
from livedrummer.kit.vocabulary import PieceKind, Zone

BEATER_LENGTH_M = 0.20
BEATER_MAX_RAD = 0.9  # beater angle at full foot lift
PEDAL_MAX_RAD = 0.35


@dataclass(frozen=True, slots=True)
class VibrationParams:
    max_angle_rad: float = 0.12
    eta: float = 0.08  # damping per second (0..1: smaller decays faster)
    beta: float = 2 * np.pi * 3.0  # rad/s
    glow_tau_s: float = 0.15


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
    dt = times - hit_s[k]
    if choke_s.size:
        c = np.searchsorted(choke_s, times, side="right") - 1
        choked = (c >= 0) & (choke_s[np.maximum(c, 0)] >= hit_s[k])
        live &= ~choked
    angle = hit_velocity[k] * p.max_angle_rad * np.power(p.eta, dt) * np.sin(p.beta * dt)
    return np.where(live, angle, 0.0)


def glow(times: np.ndarray, hit_s: np.ndarray, hit_velocity: np.ndarray, tau_s: float
         ) -> np.ndarray:  # fmt: skip
    if hit_s.size == 0:
        return np.zeros_like(times, dtype=np.float64)
    i = np.searchsorted(hit_s, times, side="right") - 1
    k = np.maximum(i, 0)
    return np.where(i >= 0, hit_velocity[k] * np.exp(-(times - hit_s[k]) / tau_s), 0.0)


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
    and the lift curve of the foot on its pedal (or None)."""
    p = p or VibrationParams()
    t = times.size
    swing = np.zeros((t, len(pieces)))
    lift = np.zeros((t, len(pieces)))
    lum = np.zeros((t, len(pieces)))
    for k, piece in enumerate(pieces):
        lum[:, k] = glow(times, hit_s[k], hit_velocity[k], p.glow_tau_s)
        if piece.kind is PieceKind.HIHAT:
            lift[:, k] = HIHAT_MAX_LIFT_M * np.clip(openness, 0.0, 1.0)
            if foot_lift[k] is not None:
                swing[:, k] = PEDAL_MAX_RAD * foot_lift[k]  # type: ignore[operator]
        elif piece.kind.is_cymbal:
            swing[:, k] = vibration(times, hit_s[k], hit_velocity[k], choke_s[k], p)
        elif piece.kind is PieceKind.KICK and foot_lift[k] is not None:
            swing[:, k] = BEATER_MAX_RAD * np.clip(foot_lift[k], 0.0, None)  # type: ignore[arg-type]
    return KitChannels(swing, lift, lum)
