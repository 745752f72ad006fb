"""Analytic inverse kinematics: a stick tip on a target, a foot on a pedal.

SMED places the wrist from the drum's position and solves the shoulder/elbow triangle, then
turns the wrist until the stick crosses the head plane. We keep its analytic spirit but start
from the other end, which makes the contact exact instead of approximate: choose the stick's
direction at contact (in the vertical plane through shoulder and target, meeting the surface
at the zone's pitch), step back along the stick to the grip fulcrum and along the hand (at a
grip angle to the stick, then turned part of the way towards the forearm) to the wrist, and
solve the two-bone shoulder-elbow-wrist triangle with the elbow swung back, out and down.

When that wrist is out of reach, or so close that the elbow would fold past 140 degrees (a
high crash right in front of the shoulder), or the hand would bend more than 60 degrees off
the forearm, the stick direction is turned sideways in the
surface plane, then towards the line shoulder-target (the longest reach there is), and the
first direction that fits is used. A target beyond the straight arm plus stick stays short:
``reached`` is False and :func:`livedrummer.body.rig.build_rig` refuses the kit.

Everything is vectorized over N strikes. Results are world rotations and positions of
shoulder, elbow, wrist and stick. Legs: hip-knee-ankle triangle with the knee forward, the
ball of the foot on the footboard, heel raised by an angle at rest; as the ball of the foot
lifts off the board the heel follows by only :data:`HEEL_FOLLOW` of the rise, so the ankle
flexes (:func:`foot_pitch`) the way a foot working a pedal does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body import quat
from livedrummer.body.skeleton import (
    BONE_REST_DIR,
    BONE_REST_SIDE,
    FOOT_REST_DIR,
    FOOT_REST_SIDE,
    SegmentLengths,
)

GRIP_RAD = np.radians(18.0)  # hand axis turned down from the stick axis
REACH_SLACK = 0.995  # never straighten an arm or leg completely
HEEL_UP_RAD = np.radians(28.0)
HEEL_FOLLOW = 0.3  # the heel rises this fraction of the ball of the foot's rise
SIDEWAYS_DEG = (0.0, 20.0, -20.0, 40.0, -40.0, 60.0, -60.0)
MAX_FLEXION_RAD = np.radians(140.0)  # contact poses fold the elbow no further than this
MAX_BEND_RAD = np.radians(60.0)  # hand off the forearm at contact, before HAND_FOLLOW
ELBOW_POLE = (0.6, -0.8, -1.0)  # elbow bends towards: out (x), back (-y), down (-z), chest frame
HAND_FOLLOW = 1.5  # weight of the forearm direction in the hand's direction
UP = np.array([0.0, 0.0, 1.0])


def _unit(v: np.ndarray) -> np.ndarray:
    out: np.ndarray = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)
    return out


def _rotate_about(v: np.ndarray, axis: np.ndarray, angle: np.ndarray | float) -> np.ndarray:
    return quat.rotate(quat.from_axis_angle(axis, angle), v)


def two_bone(
    root: np.ndarray, end: np.ndarray, a: float, b: float, pole: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Middle joint of a two-bone chain root-mid-end with bone lengths a, b, bent towards
    ``pole``; returns (mid, hinge axis, reached) where reached is False if the end had to be
    pulled in."""
    d = end - root
    dist = np.linalg.norm(d, axis=-1)
    reached = dist <= (a + b) * REACH_SLACK
    dist_c = np.clip(dist, abs(a - b) + 1e-6, (a + b) * REACH_SLACK)
    u = _unit(d)
    p = pole - np.sum(pole * u, axis=-1, keepdims=True) * u
    p = _unit(p)
    cos_a = (a * a + dist_c**2 - b * b) / (2 * a * dist_c)
    ang = np.arccos(np.clip(cos_a, -1.0, 1.0))
    mid = root + a * (np.cos(ang)[..., None] * u + np.sin(ang)[..., None] * p)
    hinge = _unit(quat.cross(u, p))
    return mid, hinge, reached


def _put(part: tuple[np.ndarray, ...], mask: np.ndarray, dst: tuple[np.ndarray, ...]) -> None:
    """Copy the masked rows of a candidate (row indices first) into the result arrays."""
    rows = part[0][mask]
    for a, b in zip(dst, part[1:], strict=True):
        a[rows] = b[mask]


@dataclass(frozen=True)
class ArmSolution:
    """World rotations (N, 4) per arm joint, joint positions (N, 3) and reach flags."""

    shoulder_q: np.ndarray
    elbow_q: np.ndarray
    wrist_q: np.ndarray
    stick_q: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    fulcrum: np.ndarray
    tip: np.ndarray
    reached: np.ndarray  # (N,) bool


def solve_arm(
    lengths: SegmentLengths,
    shoulder: np.ndarray,
    chest_q: np.ndarray,
    side: float,
    target: np.ndarray,
    normal: np.ndarray,
    pitch: np.ndarray,
) -> ArmSolution:
    """Arm poses putting the stick tip on ``target`` (all arrays over N strikes).

    ``side`` is +1 for the right arm, -1 for the left (the elbow swings to that side).
    """
    s = lengths
    to_t = target - shoulder
    in_plane = _unit(to_t - np.sum(to_t * normal, axis=-1, keepdims=True) * normal)
    pitch = np.asarray(pitch, dtype=np.float64)[..., None]
    preferred = np.cos(pitch) * in_plane - np.sin(pitch) * normal
    straight = _unit(to_t)  # stick in line with shoulder-target: the longest reach
    # the elbow bends out to the side and down, in the chest's frame
    px, py, pz = ELBOW_POLE
    pole = quat.rotate(chest_q, np.broadcast_to(np.array([side * px, py, pz]), to_t.shape))
    arm = s.upper_arm + s.forearm
    # closest shoulder-wrist distance that keeps the elbow flexion within MAX_FLEXION_RAD
    inner = np.pi - MAX_FLEXION_RAD
    fold_min = np.sqrt(s.upper_arm**2 + s.forearm**2 - 2 * s.upper_arm * s.forearm * np.cos(inner))
    d, wrist, fulcrum, e, a_axis = (np.zeros_like(target) for _ in range(5))
    # candidate stick directions, in order of preference: the natural one, turned in the
    # surface plane (sideways across the body), then blended towards the longest reach
    turns = [np.radians(side * a) for a in SIDEWAYS_DEG]
    blends = (0.25, 0.5, 0.75, 1.0)
    n_cands = len(turns) + len(blends)
    n = target.shape[0]
    fallback = np.full((2, n), -1)  # first candidate that reaches and folds / only reaches
    stash: list[tuple[np.ndarray, ...]] = []  # per candidate, for the rows tried
    todo = np.arange(n)
    for k in range(n_cands):
        rows = todo
        if k < len(turns):
            # (a turn of 0 is the identity: skipped, the first candidate fits most strikes)
            cand = (
                _rotate_about(preferred[rows], normal[rows], turns[k])
                if turns[k]
                else preferred[rows]
            )
        else:
            b = blends[k - len(turns)]
            cand = _unit((1.0 - b) * preferred[rows] + b * straight[rows])
        # the stroke axis: perpendicular to the stick and the surface normal
        ax = quat.cross(cand, normal[rows])
        tiny = np.linalg.norm(ax, axis=-1, keepdims=True) < 1e-6
        ax = _unit(np.where(tiny, quat.cross(cand, UP), ax))
        hand_dir = _rotate_about(cand, ax, -GRIP_RAD)
        ful = target[rows] - s.stick * cand
        wr = ful - s.hand * hand_dir
        part: tuple[np.ndarray, ...] = (rows, cand, wr, ful, hand_dir, ax)
        stash.append(part)
        dist = np.linalg.norm(wr - shoulder[rows], axis=-1)
        reach = dist <= arm * REACH_SLACK
        folds = reach & (dist >= fold_min)
        for level, ok in enumerate((folds, reach)):
            first = ok & (fallback[level, rows] < 0)
            fallback[level, rows[first]] = k
        # and the hand must not bend far off the forearm
        elb, _, _ = two_bone(shoulder[rows], wr, s.upper_arm, s.forearm, pole[rows])
        bend_ok = np.sum(_unit(wr - elb) * hand_dir, axis=-1) >= np.cos(MAX_BEND_RAD)
        take = folds & bend_ok
        _put(part, take, (d, wrist, fulcrum, e, a_axis))
        todo = rows[~take]
        if todo.size == 0:
            break
    for level in (0, 1) if todo.size else ():
        for k, part in enumerate(stash):
            rows = part[0]
            pick = np.isin(rows, todo) & (fallback[level, rows] == k)
            _put(part, pick, (d, wrist, fulcrum, e, a_axis))
            todo = np.setdiff1d(todo, rows[pick])
    if todo.size:
        last = stash[-1]
        _put(last, np.isin(last[0], todo), (d, wrist, fulcrum, e, a_axis))
    elbow, hinge, reached = two_bone(shoulder, wrist, s.upper_arm, s.forearm, pole)
    # Let the hand follow the forearm part of the way (the fingers take the rest of the angle
    # to the stick), so the wrist is not bent more than a drummer's would be.
    for _ in range(2):
        fore = _unit(wrist - elbow)
        e2 = _unit(e + HAND_FOLLOW * fore)
        w2 = fulcrum - s.hand * e2
        dist = np.linalg.norm(w2 - shoulder, axis=-1)
        ok = (dist <= arm * REACH_SLACK) & (dist >= fold_min)
        e = np.where(ok[..., None], e2, e)
        wrist = np.where(ok[..., None], w2, wrist)
        elbow, hinge, reached = two_bone(shoulder, wrist, s.upper_arm, s.forearm, pole)
    # if the wrist was pulled in, the chain ends short of it; recompute where it really is
    wrist_real = elbow + s.forearm * _unit(wrist - elbow)
    fulcrum = np.where(reached[..., None], fulcrum, wrist_real + s.hand * e)
    tip = fulcrum + s.stick * d
    # with the elbow out and down the hinge points to the drummer's left for either arm;
    # its opposite is the bone frames' x axis, as in the rest pose, so rotations stay small
    # (the four bones aimed in one call: each numpy call costs more than its arithmetic here)
    shoulder_q, elbow_q, wrist_q, stick_q = quat.align(
        BONE_REST_DIR,
        BONE_REST_SIDE,
        np.stack([_unit(elbow - shoulder), _unit(wrist_real - elbow), e, d]),
        np.stack([-hinge, -hinge, a_axis, a_axis]),  # the wrist twists with the stroke axis
    )
    return ArmSolution(
        shoulder_q, elbow_q, wrist_q, stick_q, elbow, wrist_real, fulcrum, tip, reached
    )


@dataclass(frozen=True)
class LegSolution:
    hip_q: np.ndarray
    knee_q: np.ndarray
    ankle_q: np.ndarray
    knee: np.ndarray
    ankle: np.ndarray
    toe: np.ndarray
    reached: np.ndarray


def foot_pitch(rise_m: np.ndarray, foot_m: float) -> np.ndarray:
    """How far the foot turns up at the ankle (radians) when the ball of the foot is ``rise_m``
    above the footboard and the heel follows by :data:`HEEL_FOLLOW` of that.

    A foot at rest (``rise_m <= 0``) is exactly flat: ``arcsin(sin(x))`` gives back ``x`` only
    to within a rounding step that depends on the CPU's SIMD path, so rest is set, not computed."""
    rise = np.maximum(rise_m, 0.0)
    drop = np.sin(HEEL_UP_RAD) - (1.0 - HEEL_FOLLOW) * rise / foot_m
    out: np.ndarray = np.where(rise > 0.0, HEEL_UP_RAD - np.arcsin(np.clip(drop, -1.0, 1.0)), 0.0)
    return out


def solve_leg(
    lengths: SegmentLengths, hip: np.ndarray, toe: np.ndarray, rise_m: np.ndarray | None = None
) -> LegSolution:
    """Leg poses putting the ball of the foot on ``toe`` (arrays over N samples), lifted
    ``rise_m`` (N,) above its footboard (None: on it), which flexes the ankle."""
    s = lengths
    fwd = toe - hip
    fwd = _unit(np.concatenate([fwd[..., :2], np.zeros_like(fwd[..., :1])], axis=-1))
    heel = HEEL_UP_RAD if rise_m is None else (HEEL_UP_RAD - foot_pitch(rise_m, s.foot))[..., None]
    foot_dir = np.cos(heel) * fwd - np.sin(heel) * UP
    ankle = toe - s.foot * foot_dir
    pole = fwd + 0.3 * UP
    knee, hinge, reached = two_bone(hip, ankle, s.thigh, s.shin, pole)
    ankle_real = knee + s.shin * _unit(ankle - knee)
    toe_real = ankle_real + s.foot * foot_dir
    side = hinge  # lateral axis, +x as at rest (the knee bends forward)
    hip_q, knee_q = quat.align(
        BONE_REST_DIR,
        BONE_REST_SIDE,
        np.stack([_unit(knee - hip), _unit(ankle_real - knee)]),
        np.stack([side, side]),
    )
    ankle_q = quat.align(FOOT_REST_DIR, FOOT_REST_SIDE, foot_dir, side)
    return LegSolution(hip_q, knee_q, ankle_q, knee, ankle_real, toe_real, reached)
