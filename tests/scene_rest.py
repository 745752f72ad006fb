"""A seated rest pose built from kit geometry: the drummer before the first stroke (tests only).

A stand-in for the body model (``livedrummer/body/``), which computes the real poses for
``livedrummer render``, ``display`` and the live synth (:mod:`livedrummer.render.body_scene`).
Renderer tests use this pose and its 22-joint :data:`REST_SKELETON` when they want a drummer
without animating a performance, so it lives with the tests, not in the installed package. It
follows the :mod:`livedrummer.render.scene` contract exactly, so swapping it for the body is swapping
one ``SceneFrame`` source for another.

The pose is placed from the kit, not typed in: the pelvis sits on the throne at
``kit.seat_height_m``; the right stick's tip rests just above the hi-hat and the left's above
the snare (the usual crossed grip of a right-handed player; mirrored kits swap them because the
pieces moved); the feet rest on the kick and hi-hat footboards. Elbows and knees come from a
two-bone solve with a fixed bend direction. Limits: one static pose; no balance, no joint
limits, no collision with the kit (a user kit with pieces out of reach gives stretched arms,
clamped at full extension).
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.render.scene import SceneFrame, Skeleton, Tone, empty_channels

STICK_LENGTH_M = 0.41
GRIP_FROM_TIP_M = 0.30
UPPER_ARM_M, FOREARM_M = 0.30, 0.27
THIGH_M, SHIN_M = 0.44, 0.43

REST_SKELETON = Skeleton.build(
    [
        ("pelvis", None, 0.0, 0.12, Tone.TROUSERS),
        ("spine", "pelvis", 0.12, 0.12, Tone.SHIRT),
        ("chest", "spine", 0.13, 0.12, Tone.SHIRT),
        ("neck", "chest", 0.05, 0.05, Tone.SKIN),
        ("head", "neck", 0.05, 0.105, Tone.SKIN),
        ("crown", "head", 0.0, 0.085, Tone.HAIR),
        ("r_shoulder", "chest", 0.06, 0.06, Tone.SHIRT),
        ("r_elbow", "r_shoulder", 0.05, 0.045, Tone.SHIRT),
        ("r_wrist", "r_elbow", 0.038, 0.034, Tone.SKIN),
        ("r_hand", "r_wrist", 0.034, 0.036, Tone.SKIN),
        ("l_shoulder", "chest", 0.06, 0.06, Tone.SHIRT),
        ("l_elbow", "l_shoulder", 0.05, 0.045, Tone.SHIRT),
        ("l_wrist", "l_elbow", 0.038, 0.034, Tone.SKIN),
        ("l_hand", "l_wrist", 0.034, 0.036, Tone.SKIN),
        ("r_hip", "pelvis", 0.09, 0.08, Tone.TROUSERS),
        ("r_knee", "r_hip", 0.075, 0.06, Tone.TROUSERS),
        ("r_ankle", "r_knee", 0.055, 0.045, Tone.TROUSERS),
        ("r_toe", "r_ankle", 0.045, 0.04, Tone.SHOES),
        ("l_hip", "pelvis", 0.09, 0.08, Tone.TROUSERS),
        ("l_knee", "l_hip", 0.075, 0.06, Tone.TROUSERS),
        ("l_ankle", "l_knee", 0.055, 0.045, Tone.TROUSERS),
        ("l_toe", "l_ankle", 0.045, 0.04, Tone.SHOES),
    ]
)


def two_bone(
    root: np.ndarray, target: np.ndarray, upper: float, lower: float, pole: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Middle joint and (reach-clamped) end joint of a two-bone chain bending towards ``pole``."""
    offset = target - root
    dist = float(np.linalg.norm(offset))
    u = offset / max(dist, 1e-9)
    dist = min(max(dist, abs(upper - lower) + 1e-6), upper + lower - 1e-6)
    cos_a = (upper * upper + dist * dist - lower * lower) / (2.0 * upper * dist)
    side = pole - np.dot(pole, u) * u
    w = side / max(float(np.linalg.norm(side)), 1e-9)
    middle = root + upper * (cos_a * u + np.sqrt(max(0.0, 1.0 - cos_a * cos_a)) * w)
    return middle, root + dist * u


def _surface(kit: Kit, kind: PieceKind, fallback: tuple[float, float, float]) -> np.ndarray:
    piece: Piece | None = next((p for p in kit.pieces if p.kind is kind), None)
    if piece is None:
        return np.array(fallback)
    return np.asarray(piece.position_m) + 0.03 * piece.normal


def _foot(kit: Kit, kind: PieceKind, fallback: tuple[float, float, float]) -> np.ndarray:
    piece = next((p for p in kit.pieces if p.kind is kind and p.pedal_position_m), None)
    return np.array(fallback if piece is None else piece.pedal_position_m)


def rest_frame(kit: Kit, skeleton: Skeleton = REST_SKELETON) -> SceneFrame:
    """The rest pose for ``kit`` as one :class:`SceneFrame` (see the module docstring)."""
    right = 1.0 if kit.handedness == "right" else -1.0
    seat = kit.seat_height_m
    pos: dict[str, np.ndarray] = {
        "pelvis": np.array([0.0, -0.02, seat + 0.09]),
        "spine": np.array([0.0, 0.0, seat + 0.30]),
        "chest": np.array([0.0, 0.04, seat + 0.50]),
        "neck": np.array([0.0, 0.06, seat + 0.66]),
        "head": np.array([0.0, 0.09, seat + 0.78]),
        "crown": np.array([0.0, 0.07, seat + 0.85]),
    }
    for side, sign in (("r", 1.0), ("l", -1.0)):
        pos[f"{side}_shoulder"] = np.array([0.19 * sign, 0.04, seat + 0.58])
        pos[f"{side}_hip"] = np.array([0.10 * sign, 0.0, seat + 0.08])
    # The leading hand (right for a right-handed kit) crosses over to the hi-hat.
    tips = {
        "r" if right > 0 else "l": _surface(kit, PieceKind.HIHAT, (-0.36 * right, 0.36, 0.88)),
        "l" if right > 0 else "r": _surface(kit, PieceKind.SNARE, (-0.07 * right, 0.36, 0.67)),
    }
    sticks = np.zeros((2, 2, 3), np.float32)
    for k, side in enumerate(("r", "l")):
        shoulder = pos[f"{side}_shoulder"]
        tip = tips[side]
        back = shoulder + np.array([0.0, 0.02, -0.32]) - tip
        back /= np.linalg.norm(back)
        hand = tip + GRIP_FROM_TIP_M * back
        sign = 1.0 if side == "r" else -1.0
        elbow, wrist = two_bone(
            shoulder, hand + 0.07 * back, UPPER_ARM_M, FOREARM_M, np.array([sign, -0.3, -1.0])
        )
        pos[f"{side}_elbow"] = elbow
        pos[f"{side}_wrist"] = wrist
        pos[f"{side}_hand"] = hand
        sticks[k, 0] = tip + STICK_LENGTH_M * back
        sticks[k, 1] = tip
    feet = {
        "r" if right > 0 else "l": _foot(kit, PieceKind.KICK, (0.10 * right, 0.38, 0.02)),
        "l" if right > 0 else "r": _foot(kit, PieceKind.HIHAT, (-0.28 * right, 0.26, 0.02)),
    }
    for side, pedal in feet.items():
        ankle_target = pedal + np.array([0.0, -0.12, 0.08])
        knee, ankle = two_bone(
            pos[f"{side}_hip"], ankle_target, THIGH_M, SHIN_M, np.array([0.0, 1.0, 1.0])
        )
        pos[f"{side}_knee"] = knee
        pos[f"{side}_ankle"] = ankle
        pos[f"{side}_toe"] = pedal + np.array([0.0, 0.07, 0.04])
    joints = np.array([pos[name] for name in skeleton.names], np.float32)
    return SceneFrame(joints, sticks, empty_channels(len(kit.pieces)))
