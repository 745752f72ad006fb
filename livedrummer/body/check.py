"""The physical truth of a performance: contact error, penetration, joint limits.

* **Contact error** (per played onset): distance from the playing limb's effector to the
  struck zone's target point at the onset time: the stick tip for hands, the kick beater's
  tip for the kick, the ball of the foot on the footboard for the hi-hat pedal. The target
  point lies on the surface, so this bounds the distance to the surface from above.
* **Penetration**: the deepest any stick tip goes below any piece's playing disc (within a
  slab: a drum's depth, 15 mm for cymbals), over frames sampled at ``fps`` plus every onset.
* **Joint-limit violations**: frames x joints outside ordinary human ranges
  (:data:`LIMITS_DEG`): elbow and knee flexion, wrist bend off the forearm, shoulder
  elevation from hanging, torso twist.

Sampling is chunked; the whole Groove MIDI Dataset is a few hundred thousand onsets and a
few million frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body.animation import FOOT_LIFT_M, Animation
from livedrummer.body.channels import BEATER_MAX_RAD, beater_tip
from livedrummer.body.skeleton import ARM, LEG
from livedrummer.body.targets import penetration_depth
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.sticking.result import Sticking

CHUNK = 40_000

#: (low, high) degrees.
LIMITS_DEG: dict[str, tuple[float, float]] = {
    "elbow_flexion": (0.0, 155.0),
    "wrist_bend": (0.0, 85.0),
    "shoulder_elevation": (0.0, 160.0),
    "knee_flexion": (0.0, 160.0),
    "torso_twist": (-45.0, 45.0),
}


@dataclass
class CheckResult:
    notes: int
    not_played: int
    contact_error_m: np.ndarray  # per played onset
    penetration_m: float
    penetration_at_s: float
    joint_limit_violations: int
    violations_by_limit: dict[str, int]
    frames: int

    def as_json(self) -> dict[str, object]:
        e = self.contact_error_m * 1000.0
        return {
            "notes": self.notes,
            "not_played": self.not_played,
            "contact_error_mm": contact_figures(e),
            "penetration_mm": round(self.penetration_m * 1000.0, 4),
            "penetration_at_s": round(self.penetration_at_s, 4),
            "joint_limit_violations": self.joint_limit_violations,
            "violations_by_limit": self.violations_by_limit,
            "frames": self.frames,
        }


def contact_figures(error_mm: np.ndarray) -> dict[str, float] | None:
    """Max, p99, mean and the share within 5 mm of contact errors (mm); ``None`` for none:
    no note played is no measurement, not a perfect one."""
    if not error_mm.size:
        return None
    return {
        "max": round(float(error_mm.max()), 6),
        "p99": round(float(np.percentile(error_mm, 99)), 6),
        "mean": round(float(error_mm.mean()), 6),
        "within_5mm": round(float(np.mean(error_mm <= 5.0)), 6),
    }


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = np.sum(a * b, axis=-1) / np.maximum(
        np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1), 1e-12
    )
    out: np.ndarray = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return out


def joint_measures(world_p: np.ndarray, twist_rad: np.ndarray) -> dict[str, np.ndarray]:
    """Per frame (T, k) values in degrees of each limited quantity."""
    out: dict[str, list[np.ndarray]] = {k: [] for k in LIMITS_DEG}
    down = np.array([0.0, 0.0, -1.0])
    for side in ("R", "L"):
        sh, el, wr, st, _ = ARM[side]
        upper = world_p[:, el] - world_p[:, sh]
        fore = world_p[:, wr] - world_p[:, el]
        hand = world_p[:, st] - world_p[:, wr]
        out["elbow_flexion"].append(_angle(upper, fore))
        out["wrist_bend"].append(_angle(fore, hand))
        out["shoulder_elevation"].append(_angle(np.broadcast_to(down, upper.shape), upper))
        hip, knee, ankle, _ = LEG[side]
        out["knee_flexion"].append(
            _angle(world_p[:, knee] - world_p[:, hip], world_p[:, ankle] - world_p[:, knee])
        )
    out["torso_twist"].append(np.degrees(twist_rad))
    return {k: np.stack(v, axis=-1) for k, v in out.items()}


def contact_errors(anim: Animation, sticking: Sticking) -> tuple[np.ndarray, np.ndarray]:
    """(played onset indices, contact error in metres for each)."""
    on = sticking.onsets
    played = np.flatnonzero((sticking.limb >= 0) & (sticking.piece >= 0))
    errors = np.zeros(played.size)
    kit = anim.rig.kit
    for start in range(0, played.size, CHUNK):
        idx = played[start : start + CHUNK]
        t = on["time_s"][idx].astype(np.float64)
        _, wp = anim.world(t)
        limb = sticking.limb[idx]
        piece = sticking.piece[idx].astype(np.int64)
        zone = on["zone"][idx].astype(np.int64)
        point, _, _ = anim.rig.targets.lookup(piece, zone, on["openness"][idx])
        err = np.zeros(idx.size)
        for code, side in ((0, "R"), (1, "L")):
            m = limb == code
            err[m] = np.linalg.norm(wp[m, ARM[side][4]] - point[m], axis=-1)
        for code, side in ((2, "r"), (3, "l")):
            m = limb == code
            if not m.any():
                continue
            lift = anim.foot_lift(side, t[m])
            toe = wp[m, LEG[side.upper()][3]]
            pedal = anim.toe_target(side, t[m]) - (FOOT_LIFT_M * lift)[:, None] * np.array(
                [0.0, 0.0, 1.0]
            )
            e = np.linalg.norm(toe - pedal, axis=-1)
            kicks = np.array([kit.pieces[p].kind is PieceKind.KICK for p in piece[m]])
            for pi in np.unique(piece[m][kicks]):
                sel = kicks & (piece[m] == pi)
                tip = beater_tip(kit.pieces[pi], BEATER_MAX_RAD * lift[sel])
                e[sel] = np.linalg.norm(tip - point[m][sel], axis=-1)
            err[m] = e
        errors[start : start + idx.size] = err
    return played, errors


def check(anim: Animation, sticking: Sticking, fps: float = 200.0) -> CheckResult:
    on = sticking.onsets
    played, errors = contact_errors(anim, sticking)
    end = float(on["time_s"].max()) + 1.0 if on.size else 1.0
    start = float(on["time_s"].min()) - 0.5 if on.size else 0.0
    frames = np.arange(start, end, 1.0 / fps)
    frames = np.sort(np.concatenate([frames, on["time_s"][played].astype(np.float64)]))
    worst, worst_t = 0.0, 0.0
    counts = dict.fromkeys(LIMITS_DEG, 0)
    tips = [ARM["R"][4], ARM["L"][4]]
    for s in range(0, frames.size, CHUNK):
        t = frames[s : s + CHUNK]
        _, wp = anim.world(t)
        depth = penetration_depth(anim.rig.surfaces, wp[:, tips]).max(axis=-1)
        k = int(np.argmax(depth))
        if depth[k] > worst:
            worst, worst_t = float(depth[k]), float(t[k])
        for name, values in joint_measures(wp, anim.torso.twist(t)).items():
            lo, hi = LIMITS_DEG[name]
            counts[name] += int(np.count_nonzero((values < lo - 1e-9) | (values > hi + 1e-9)))
    return CheckResult(
        notes=int(played.size),
        not_played=int(on.size - played.size),
        contact_error_m=errors,
        penetration_m=worst,
        penetration_at_s=worst_t,
        joint_limit_violations=int(sum(counts.values())),
        violations_by_limit=counts,
        frames=int(frames.size),
    )
