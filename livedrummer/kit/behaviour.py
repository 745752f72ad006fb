"""What each kind of piece does when it is struck or pedalled: one table, read everywhere.

The body computes a piece's motion channels (:mod:`livedrummer.body.channels`), the scene maps
them to drawing channels (:mod:`livedrummer.render.body_scene`) and the kit mesh moves its parts
(:mod:`livedrummer.render.kitmesh`). All three used to ask ``if piece.kind is ...``; now they
read one :class:`Behaviour` per :class:`~livedrummer.kit.vocabulary.PieceKind`, so a new kind,
or a kind that should move differently, is one row of :data:`BEHAVIOURS`.

* ``hit``: what a stick hit does. :attr:`HitMotion.SWING` is a cymbal's slow, wide, damped
  swing on its felt; :attr:`HitMotion.SHAKE` is a drum's short, fast shake on its mount. Both are
  the same decaying sinusoid (the virtual-drummer paper's), with the piece's own amplitude and
  frequency from :func:`swing_of`.
* ``pedal``: what the foot drives. :attr:`PedalMotion.BEATER` (the kick: beater and footboard),
  :attr:`PedalMotion.HIHAT` (the hi-hat: footboard, with the top cymbal lifted by the pedal
  controller's openness). ``pedal_swing_rad`` is the body's swing channel per unit of foot lift.

Cymbal size. A larger cymbal swings slower (a pendulum on the felt: frequency as one over the
square root of the diameter) and through a wider angle (its edge carries more of the hit's
momentum past the felt: angle as the square root of the diameter), scaled by the kind's
``weight`` (a ride is heavy). A kit file may set a cymbal's ``swing_deg`` (its largest swing at
full velocity); without it the angle comes from the diameter, 16" giving the paper's default.
Limits: shakes and swings tilt about one axis each; stands and tom mounts never move.

Footboards hinge at their heel end (:data:`FOOTBOARD_HINGE_M` from the ball of the foot, which
rests at the kit's ``pedal_position_m``) and rise from :data:`FOOTBOARD_REST_RAD`;
:func:`footboard_angle` is the board's turn that keeps the ball of a lifted foot on the board.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from livedrummer.kit.model import Piece
from livedrummer.kit.vocabulary import PieceKind


class HitMotion(Enum):
    NONE = "none"
    SWING = "swing"
    SHAKE = "shake"


class PedalMotion(Enum):
    NONE = "none"
    BEATER = "beater"
    HIHAT = "hihat"


@dataclass(frozen=True, slots=True)
class Behaviour:
    """How one kind of piece moves (see the module docstring)."""

    hit: HitMotion = HitMotion.NONE
    pedal: PedalMotion = PedalMotion.NONE
    weight: float = 1.0  # scales the hit's angle
    pedal_swing_rad: float = 0.0  # swing channel per unit foot lift (pedal pieces)


BEHAVIOURS: dict[PieceKind, Behaviour] = {
    PieceKind.KICK: Behaviour(pedal=PedalMotion.BEATER, pedal_swing_rad=0.9),
    PieceKind.SNARE: Behaviour(HitMotion.SHAKE, weight=0.4),
    PieceKind.TOM: Behaviour(HitMotion.SHAKE),
    PieceKind.HIHAT: Behaviour(pedal=PedalMotion.HIHAT, pedal_swing_rad=0.35),
    PieceKind.CRASH: Behaviour(HitMotion.SWING),
    PieceKind.RIDE: Behaviour(HitMotion.SWING, weight=0.6),
    PieceKind.SPLASH: Behaviour(HitMotion.SWING),
    PieceKind.CHINA: Behaviour(HitMotion.SWING, weight=0.9),
    PieceKind.COWBELL: Behaviour(),
    PieceKind.TAMBOURINE: Behaviour(HitMotion.SHAKE, weight=1.5),
    PieceKind.PERCUSSION: Behaviour(),
}

#: The paper's cymbal swing (16" reference): largest angle, frequency and damping per second.
SWING_REFERENCE_DIAMETER_M = 16 * 0.0254
SWING_MAX_RAD = 0.12
SWING_HZ = 3.0
SWING_ETA = 0.08
#: A drum's shake on its mount: small, fast and short.
SHAKE_MAX_RAD = 0.035
SHAKE_HZ = 9.0
SHAKE_ETA = 0.0005

FOOTBOARD_HINGE_M = 0.14  # heel hinge to the ball of the foot, along the board
FOOTBOARD_REST_RAD = math.radians(14.0)  # the board rises this much towards the piece
FOOTBOARD_MAX_RAD = math.radians(40.0)


def behaviour(kind: PieceKind) -> Behaviour:
    return BEHAVIOURS[kind]


@dataclass(frozen=True, slots=True)
class Swing:
    """A piece's hit motion: ``angle * velocity * eta**dt * sin(2 pi hz dt)``."""

    max_angle_rad: float
    hz: float
    eta: float


def swing_of(piece: Piece) -> Swing:
    """The hit motion of ``piece``: zero amplitude for a piece whose hits do not move it."""
    b = BEHAVIOURS[piece.kind]
    size = 2.0 * piece.radius_m / SWING_REFERENCE_DIAMETER_M
    if b.hit is HitMotion.SWING:
        if piece.swing_deg is not None:
            angle = math.radians(piece.swing_deg)
        else:
            angle = SWING_MAX_RAD * b.weight * math.sqrt(size)
        return Swing(angle, SWING_HZ / math.sqrt(size), SWING_ETA)
    if b.hit is HitMotion.SHAKE:
        return Swing(SHAKE_MAX_RAD * b.weight, SHAKE_HZ, SHAKE_ETA)
    return Swing(0.0, 0.0, 1.0)


def footboard_angle(rise_m: np.ndarray) -> np.ndarray:
    """The footboard's turn up from rest (radians) that lifts the ball of the foot, on the board
    :data:`FOOTBOARD_HINGE_M` from the hinge, by ``rise_m`` (clipped to the board's travel).

    At rest (``rise_m <= 0``) the board is exactly at 0: ``arcsin(sin(x)) - x`` is zero only to
    within a rounding step that depends on the CPU's SIMD path, so rest is set, not computed."""
    rise = np.asarray(rise_m, np.float64)
    s = math.sin(FOOTBOARD_REST_RAD) + rise / FOOTBOARD_HINGE_M
    angle = np.arcsin(np.clip(s, -1.0, 1.0)) - FOOTBOARD_REST_RAD
    out: np.ndarray = np.where(rise > 0.0, np.clip(angle, 0.0, FOOTBOARD_MAX_RAD), 0.0)
    return out
