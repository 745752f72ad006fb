"""From an assigned performance to motion curves, and sampling them for any times.

Order of work (SMED's): the torso first (it carries the shoulders), then at every hand onset
the arm IK with the torso where it will be at that instant, then stroke keys per limb, then
per-joint CTB splines of rotation vectors. Sampling evaluates every curve for an array of
times at once and runs the forward kinematics once. Because each spline passes through its
contact key exactly and the contact key *is* the IK solution for that instant, the stick tip
is on the target at the onset time up to floating-point error.

Hands: each joint's contact rotation is the base (the shoulder's in the world frame, so a
hovering arm stays over its drum while the torso twists and sways under it; the others
local to their parent); a key with lift λ turns the joint about its stroke axis (the local x
axis, signed so the tip rises) by λ times its amplitude (expression shares: wrist, elbow,
shoulder; the grip follows the wrist at a third; the elbow never folds past 150 degrees).

Keeping the sticks out of the kit takes two steps. When the curves are built, a clearance
search probes the arcs next to every raised key and lowers preparations (or raises, then
lowers, travel arcs) that dip into a piece. At sampling, :func:`guard_sticks` turns a stick
about its grip out of any surface it would still enter (never at a contact, where the tip
lies on the surface).

Feet: a scalar lift spline raises the ball of the foot above the footboard and the leg IK
runs per sample (the heel follows only part of the rise, so the ankle flexes: see
:func:`~livedrummer.body.ik.foot_pitch`); the same scalar drives the kick beater and the
hi-hat pedal, and the hi-hat foot also follows the pedal controller (openness). A limb without
notes hovers over its home piece (hands) or rests on its pedal (feet).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from livedrummer.body import fk, quat, spline
from livedrummer.body.expression import Expression
from livedrummer.body.ik import ArmSolution, solve_leg
from livedrummer.body.ready import ReadyParams, ready_keys, solve_ready
from livedrummer.body.rig import Rig, neutral_world
from livedrummer.body.secondary import BOB_KINDS, SecondaryParams, Torso, TorsoStyle, build_torso
from livedrummer.body.skeleton import ARM, LEG, N_JOINTS, J
from livedrummer.body.strike import leg_locals, solve_strike, to_local
from livedrummer.body.strokes import (
    AFTER,
    BEFORE,
    CONTACT,
    MERGED,
    TRAVEL,
    Keys,
    StrokeParams,
    lagged_times,
    stroke_keys,
)
from livedrummer.body.targets import Surfaces, penetration_depth
from livedrummer.kit.vocabulary import ZONES, Limb, PieceKind, Zone
from livedrummer.sticking.result import LIMBS, Sticking

X = np.array([1.0, 0.0, 0.0])
#: Shoulder curves hold world rotations, so a hovering arm stays put while the torso twists
#: and sways under it (only the shoulder joint's position moves); the rest are local.
PARENT_IS_CHEST = {j: j in (ARM["R"][0], ARM["L"][0]) for j in range(N_JOINTS)}
FOOT_LIFT_M = 0.07
REST_LIFT = 0.15  # a foot with nothing to play hovers this far above its footboard
ELBOW_MAX_RAD = np.radians(150.0)
GUARD_TOLERANCE_M = 0.0005
GUARD_ANGLES_RAD = np.radians([3.0, 6.0, 10.0, 15.0, 22.0, 30.0, 40.0, 55.0, 70.0])
PROBES = 2  # samples per segment next to a key, for the clearance search
TRIES_SCALE = (0.6, 0.3, 0.0)  # factors on a stroke key's lift
TRIES_TRAVEL = (0.4, 0.8, -0.3)  # added to a travel key's lift
PEDAL_WINDOW_S = 0.05  # the controller's openness fades out this close to a pedal stroke
READY = ReadyParams()  # the waiting hand (livedrummer.body.ready)


@dataclass(frozen=True)
class JointCurve:
    time_s: np.ndarray  # (K,)
    rotvec: np.ndarray  # (K, 3)
    tension: np.ndarray
    continuity: np.ndarray
    bias: np.ndarray | None = None  # Expression.ctb_bias at the contacts

    def sample(self, times: np.ndarray) -> np.ndarray:
        rv = spline.evaluate(
            self.time_s, self.rotvec, times, self.tension, self.continuity, self.bias
        )
        return quat.exp(rv)


@dataclass(frozen=True)
class FootCurve:
    time_s: np.ndarray
    lift: np.ndarray
    tension: np.ndarray
    continuity: np.ndarray
    contact_s: np.ndarray  # note times, for the pedal under the foot
    pedal_m: np.ndarray  # (n, 3) footboard under the foot at each note
    follows_hihat: bool

    def sample_lift(self, times: np.ndarray) -> np.ndarray:
        lift = spline.evaluate(self.time_s, self.lift, times, self.tension, self.continuity)
        out: np.ndarray = np.maximum(lift, 0.0)
        return out

    def pedal(self, times: np.ndarray) -> np.ndarray:
        return np.stack(
            [np.interp(times, self.contact_s, self.pedal_m[:, k]) for k in range(3)], axis=-1
        )


@dataclass(frozen=True)
class Openness:
    """Hi-hat openness (0..1) as a step function of time."""

    time_s: np.ndarray
    value: np.ndarray

    def __call__(self, times: np.ndarray) -> np.ndarray:
        if self.time_s.size == 0:
            return np.zeros_like(times)
        i = np.searchsorted(self.time_s, times, side="right") - 1
        return np.where(i >= 0, self.value[np.maximum(i, 0)], self.value[0])


@dataclass(frozen=True)
class Animation:
    rig: Rig
    torso: Torso
    arms: dict[str, dict[int, JointCurve]]  # side -> joint index -> curve
    feet: dict[str, FootCurve | None]
    openness: Openness
    hihat_piece: int  # -1 when the kit has none
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    def foot_lift(self, side: str, times: np.ndarray) -> np.ndarray:
        curve = self.feet[side]
        on_hihat = self._foot_on_hihat(side)
        if curve is not None:
            lift = curve.sample_lift(times)
        else:  # resting: on the hi-hat pedal it follows the pedal, else it hovers a little
            lift = np.full_like(times, 0.0 if on_hihat else REST_LIFT)
        if (curve is None or curve.follows_hihat) and on_hihat:
            open_ = self.openness(times)
            if curve is not None and curve.contact_s.size:
                # the pedal is down at a pedal stroke whatever the controller last said
                c = curve.contact_s
                i = np.clip(np.searchsorted(c, times), 1, c.size)
                near = np.minimum(
                    np.abs(times - c[i - 1]), np.abs(times - c[np.minimum(i, c.size - 1)])
                )
                open_ = open_ * np.clip(near / PEDAL_WINDOW_S, 0.0, 1.0)
            lift = np.maximum(lift, open_)
        return lift

    def _foot_on_hihat(self, side: str) -> bool:
        if self.hihat_piece < 0:
            return False
        piece = self.rig.kit.pieces[self.hihat_piece]
        foot = piece.limb_for(Zone.PEDAL)
        return (foot is Limb.RF) == (side == "r")

    def locals(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (T, J, 4) and root positions (T, 3) at ``times``."""
        local, root, _, _ = self.solve(times)
        return local, root

    def world(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (T, J, 4) and positions (T, J, 3) at ``times``."""
        _, _, wq, wp = self.solve(times)
        return wq, wp

    def solve(
        self, times: np.ndarray, guard: bool = True
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Local rotations, root positions, world rotations and positions at ``times``, with
        the stick guard applied (see :func:`guard_sticks`)."""
        local, root = self._curves(times)
        wq, wp = fk.forward(self.rig.skeleton, local, root)
        if guard:
            guard_sticks(self.rig, local, wq, wp)
        return local, root, wq, wp

    def _curves(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        times = np.asarray(times, dtype=np.float64)
        t = times.size
        local = quat.identity((t, N_JOINTS))
        for name, q in self.torso.locals(times).items():
            local[:, J[name]] = q
        chest_w = quat.mul(local[:, J["lower_back"]], local[:, J["chest"]])
        for joints in self.arms.values():
            for j, curve in joints.items():
                local[:, j] = curve.sample(times)
                if PARENT_IS_CHEST[j]:
                    local[:, j] = to_local(chest_w, local[:, j])[0]
        skel = self.rig.skeleton
        for side in ("r", "l"):
            hip_j, knee_j, ankle_j, _ = LEG[side.upper()]
            hip = skel.root_m + skel.offsets[hip_j]
            toe = self.toe_target(side, times)
            rise = FOOT_LIFT_M * self.foot_lift(side, times)
            leg = solve_leg(skel.lengths, np.broadcast_to(hip, toe.shape), toe, rise)
            local[:, hip_j], local[:, knee_j], local[:, ankle_j] = leg_locals(leg)
        return local, np.broadcast_to(skel.root_m, (t, 3)).copy()

    def toe_target(self, side: str, times: np.ndarray) -> np.ndarray:
        curve = self.feet[side]
        if curve is not None:
            base = curve.pedal(times)
        else:
            base = np.broadcast_to(self.extra[f"{side}_rest_toe"], (times.size, 3))
        lift = self.foot_lift(side, times)
        out: np.ndarray = base + (FOOT_LIFT_M * lift)[:, None] * np.array([0.0, 0.0, 1.0])
        return out


def guard_sticks(rig: Rig, local: np.ndarray, wq: np.ndarray, wp: np.ndarray) -> None:
    """The stick cannot pass through a drum or cymbal: where a stick tip is more than
    :data:`GUARD_TOLERANCE_M` inside a piece, the grip lets the stick turn about its fulcrum
    (away from that surface) by the smallest of a few angles that frees it. Updates the
    arrays in place. Contacts are untouched: a tip on a surface is not inside it. This is the
    last line of defence behind the clearance search done when the curves are built."""
    for side in ("R", "L"):
        _, _, wr_j, st_j, tip_j = ARM[side]
        depth, which = _inside(rig.surfaces, wp[:, tip_j])
        bad = np.flatnonzero(depth > GUARD_TOLERANCE_M)
        if bad.size == 0:
            continue
        fulcrum = wp[bad, st_j]
        v = wp[bad, tip_j] - fulcrum
        n = rig.surfaces.normal[which[bad]]
        axis = quat.cross(v, n)
        axis /= np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-12)
        chosen = np.zeros(bad.size)
        left = np.ones(bad.size, dtype=bool)
        for angle in GUARD_ANGLES_RAD:
            tip = fulcrum + quat.rotate(quat.from_axis_angle(axis, angle), v)
            free = left & (penetration_depth(rig.surfaces, tip) <= GUARD_TOLERANCE_M)
            chosen[free] = angle
            left &= ~free
        chosen[left] = GUARD_ANGLES_RAD[-1]
        turn = quat.from_axis_angle(axis, chosen)
        wq[bad, st_j] = quat.mul(turn, wq[bad, st_j])
        local[bad, st_j] = to_local(wq[bad, wr_j], wq[bad, st_j])[0]
        wq[bad, tip_j] = wq[bad, st_j]
        wp[bad, tip_j] = fulcrum + quat.rotate(turn, v)


def _inside(s: Surfaces, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Depth inside the deepest piece and that piece's index, per point."""
    rel = points[:, None, :] - s.centre
    h = np.sum(rel * s.normal, axis=-1)
    radial = np.linalg.norm(rel - h[..., None] * s.normal, axis=-1)
    depth = np.where((radial <= s.radius) & (h < 0.0) & (h > -s.slab), -h, 0.0)
    return depth.max(axis=-1), depth.argmax(axis=-1)


def hihat_openness(
    onsets: np.ndarray, controls: np.ndarray, hihat_cc: int = 4, cc_open: np.ndarray | None = None
) -> Openness:
    """Openness over time from pedal-controller events (``cc_open`` maps 0..127 to openness;
    default 1 - value/127), else from the hi-hat onsets' own openness."""
    from livedrummer.timeline.events import ControlKind

    table = cc_open if cc_open is not None else 1.0 - np.arange(128) / 127.0
    ped = controls[controls["kind"] == ControlKind.HIHAT_PEDAL] if controls.size else controls
    if ped.size:
        return Openness(ped["time_s"].astype(np.float64), table[ped["value"]])
    hat = onsets[~np.isnan(onsets["openness"])] if onsets.size else onsets
    return Openness(hat["time_s"].astype(np.float64), hat["openness"].astype(np.float64))


def _spine(rig: Rig, torso: Torso, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Chest world rotation (T, 4) and the right and left shoulder positions (T, 3)."""
    skel = rig.skeleton
    lower, chest = torso.back(times)
    chest_w = quat.mul(lower, chest)
    base = (
        skel.root_m + skel.offsets[J["lower_back"]] + quat.rotate(lower, skel.offsets[J["chest"]])
    )
    return (
        chest_w,
        base + quat.rotate(chest_w, skel.offsets[ARM["R"][0]]),
        base + quat.rotate(chest_w, skel.offsets[ARM["L"][0]]),
    )


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    out: np.ndarray = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def _home_piece(rig: Rig, limb: Limb) -> int:
    pieces = rig.kit.pieces
    for kind in (PieceKind.HIHAT, PieceKind.SNARE) if limb is Limb.RH else (PieceKind.SNARE,):
        for i, p in enumerate(pieces):
            if p.kind is kind and p.preferred_limb is limb:
                return i
    for i, p in enumerate(pieces):
        if p.preferred_limb is limb:
            return i
    return (
        next(i for i, p in enumerate(pieces) if p.kind is PieceKind.SNARE)
        if any(p.kind is PieceKind.SNARE for p in pieces)
        else 0
    )


def animate(
    rig: Rig,
    sticking: Sticking,
    beats: np.ndarray,
    openness: Openness,
    expression: Expression | None = None,
    strokes: StrokeParams | None = None,
    secondary: SecondaryParams | None = None,
    pause: Callable[[], None] | None = None,
    memo: ClearanceMemo | None = None,
) -> Animation:
    """The curves of a whole performance (see the module docstring). ``pause``, when given,
    is called between the steps (torso, each arm, feet, each clearance search; none takes
    more than a few milliseconds), so a live caller can answer input in the meantime; it
    must not change anything this call reads. ``memo``: the clearance search's settings
    carried from the previous call over an overlapping window (see :func:`_clear_kit`)."""
    step = pause or _nothing
    ex = expression or Expression()
    sp = strokes or StrokeParams()
    sec = replace(secondary or SecondaryParams(), twist_cap_deg_s=ex.turn_speed_deg_s)
    kit = rig.kit
    on = sticking.onsets
    played = (sticking.limb >= 0) & (sticking.piece >= 0)
    idx_all = np.flatnonzero(played)
    piece = sticking.piece.astype(np.int64)
    zone = on["zone"].astype(np.int64)
    vel = on["velocity"].astype(np.float64) / 127.0
    # each piece kind's amplitude (Expression.piece_amplitude) scales its strokes' lift
    gain = np.array([ex.piece_gain(p.kind.value) for p in kit.pieces] or [1.0])
    lift_all = vel * gain[np.maximum(piece, 0)]
    times = on["time_s"].astype(np.float64)
    elasticity = np.array([p.elasticity for p in kit.pieces])
    hihat = next((i for i, p in enumerate(kit.pieces) if p.kind is PieceKind.HIHAT), -1)

    hands = idx_all[sticking.limb[idx_all] <= 1]
    h_point, _, _ = rig.targets.lookup(piece[hands], zone[hands], on["openness"][hands])
    _, wp0 = neutral_world(rig.skeleton, sec.lean_deg)
    head_m = wp0[0, J["head"]]
    kinds = np.array([p.kind.value for p in kit.pieces] or ["none"])
    bob_mask = played & np.isin(kinds[np.maximum(piece, 0)], list(BOB_KINDS))
    torso = build_torso(
        sec,
        ex.twist_fraction,
        np.radians(ex.back_amplitude_deg),
        np.radians(ex.head_amplitude_deg),
        np.asarray(beats, dtype=np.float64),
        times[hands],
        h_point,
        head_m,
        times[bob_mask],
        vel[bob_mask],
        times[played],
        TorsoStyle(
            ex.back_frequency,
            ex.head_frequency,
            np.radians(ex.side_sway_deg),
            np.radians(ex.head_tilt_deg),
        ),
    )
    step()

    amp_w, amp_e, amp_s = ex.joint_amplitude_rad(sp.full_amplitude_rad)
    ts_w, ts_e, ts_s = ex.joint_time_scale()
    arms: dict[str, dict[int, JointCurve]] = {}
    arm_keys: dict[str, _ArmKeys] = {}
    extra: dict[str, np.ndarray] = {}
    for code, side in ((0, "r"), (1, "l")):
        notes = idx_all[sticking.limb[idx_all] == code]
        sh_j, el_j, wr_j, st_j, _ = ARM[side.upper()]
        t = times[notes]
        if notes.size == 0:
            home = _home_piece(rig, LIMBS[code])
            t = np.zeros(1)
            pz = (np.array([home]), np.array([ZONES.index(kit.pieces[home].zones[0])]))
            lift_v = np.array([READY.lift])
            openn = np.array([np.nan])
        else:
            pz = (piece[notes], zone[notes])
            lift_v = lift_all[notes]
            openn = on["openness"][notes]
        chest_q, r_sh, l_sh = _spine(rig, torso, t)
        shoulder = r_sh if side == "r" else l_sh
        if notes.size == 0:  # a hand with nothing to play waits ready over its home piece
            sol, point, normal = solve_ready(
                rig, code, shoulder, chest_q, pz[0], pz[1], openn, READY.height_m
            )
        else:
            sol, point, normal = solve_strike(rig, code, shoulder, chest_q, pz[0], pz[1], openn)
        poses = _ArmPoses.of(sol, shoulder, point, normal, (amp_s, amp_e, amp_w), side)
        scales = {sh_j: ts_s, el_j: ts_e, wr_j: ts_w * (1 - sp.lag), st_j: ts_w * (1 - 2 * sp.lag)}
        if notes.size == 0:
            keys = Keys(t, lift_v, np.array([0]), np.array([0]), np.array([0]), t)
        else:
            target_id = pz[0] * len(ZONES) + pz[1]
            keys = stroke_keys(t, target_id, lift_v, elasticity[pz[0]], sp, pz[0])
            ready = ready_keys(keys, t, READY)
            if ready.time_s.size:  # the ready poses ride behind the contacts as virtual notes
                keys = ready.keys
                r = ready.note
                chest_r, r_sh_r, l_sh_r = _spine(rig, torso, ready.time_s)
                shoulder_r = r_sh_r if side == "r" else l_sh_r
                sol_r, point_r, normal_r = solve_ready(
                    rig, code, shoulder_r, chest_r, pz[0][r], pz[1][r], openn[r], READY.height_m
                )
                poses = poses.then(
                    _ArmPoses.of(sol_r, shoulder_r, point_r, normal_r, (amp_s, amp_e, amp_w), side)
                )
        arm = _ArmKeys(keys, poses.base, poses.signed, poses.amps, scales, ex.ctb_bias)
        arm_keys[side] = arm
        arms[side] = arm.curves()
        step()

    feet: dict[str, FootCurve | None] = {}
    for code, side in ((2, "r"), (3, "l")):
        notes = idx_all[sticking.limb[idx_all] == code]
        if notes.size == 0:
            feet[side] = None
            pedals = [p for p in kit.pieces if p.pedal_position_m is not None]
            hip = rig.skeleton.root_m + rig.skeleton.offsets[LEG[side.upper()][0]]
            best = min(pedals, key=lambda p: abs(p.pedal_position_m[0] - hip[0]))  # type: ignore[index]
            extra[f"{side}_rest_toe"] = np.asarray(best.pedal_position_m, dtype=np.float64)
            continue
        pz = (piece[notes], zone[notes])
        pedal_m = np.array(
            [kit.pieces[i].pedal_position_m or kit.pieces[i].position_m for i in pz[0]],
            dtype=np.float64,
        )
        keys = stroke_keys(
            times[notes], pz[0] * len(ZONES) + pz[1], lift_all[notes], elasticity[pz[0]], sp
        )
        feet[side] = FootCurve(
            keys.time_s,
            keys.lift,
            np.where(keys.kind == CONTACT, 0.0, 1.0),
            np.where(keys.kind == CONTACT, -1.0, 0.0),
            times[notes],
            pedal_m,
            follows_hihat=any(kit.pieces[i].kind is PieceKind.HIHAT for i in set(pz[0].tolist())),
        )
    anim = Animation(rig, torso, arms, feet, openness, hihat, extra)
    step()
    _clear_kit(anim, arm_keys, step, memo)
    return anim


def _nothing() -> None:
    return None


@dataclass(frozen=True)
class _ArmPoses:
    """Per note (contact, or ready: see :mod:`~livedrummer.body.ready`), each arm joint's
    base rotation, the sign that lifts its stick and its full-lift amplitude."""

    base: dict[int, np.ndarray]
    signed: dict[int, np.ndarray]
    amps: dict[int, np.ndarray]

    @classmethod
    def of(
        cls,
        sol: ArmSolution,
        shoulder: np.ndarray,
        point: np.ndarray,
        normal: np.ndarray,
        amp: tuple[float, float, float],
        side: str,
    ) -> _ArmPoses:
        amp_s, amp_e, amp_w = amp
        sh_j, el_j, wr_j, st_j, _ = ARM[side.upper()]
        world = {sh_j: sol.shoulder_q, el_j: sol.elbow_q, wr_j: sol.wrist_q, st_j: sol.stick_q}
        # the shoulder's stays in the world frame (see Animation.locals), the rest local
        base = dict(zip((sh_j, el_j, wr_j, st_j), to_local(None, *world.values()), strict=True))
        pivots = {sh_j: shoulder, el_j: sol.elbow, wr_j: sol.wrist, st_j: sol.fulcrum}
        n = shoulder.shape[0]
        flexion = _angle(sol.elbow - shoulder, sol.wrist - sol.elbow)
        amps = {
            sh_j: np.full(n, amp_s),
            # a stroke never folds the elbow past ELBOW_MAX_RAD
            el_j: np.clip(ELBOW_MAX_RAD - flexion, 0.0, amp_e),
            wr_j: np.full(n, amp_w),
            st_j: np.full(n, amp_w / 3.0),
        }
        signed = {}
        for j in (sh_j, el_j, wr_j, st_j):
            axis_w = quat.rotate(world[j], X)
            rise = np.sum(axis_w * quat.cross(point - pivots[j], normal), axis=-1)
            signed[j] = np.where(rise >= 0, 1.0, -1.0)
        return cls(base, signed, amps)

    def then(self, more: _ArmPoses) -> _ArmPoses:
        """These poses followed by ``more`` (indices n.. are ``more``'s)."""

        def cat(a: dict[int, np.ndarray], b: dict[int, np.ndarray]) -> dict[int, np.ndarray]:
            return {j: np.concatenate([a[j], b[j]]) for j in a}

        return _ArmPoses(
            cat(self.base, more.base), cat(self.signed, more.signed), cat(self.amps, more.amps)
        )


@dataclass
class _ArmKeys:
    """What a hand's curves are built from, kept so travel arcs can be raised."""

    keys: Keys
    base: dict[int, np.ndarray]  # joint -> (n, 4) contact rotation per note
    signed: dict[int, np.ndarray]  # joint -> (n,) direction of the lift
    amps: dict[int, np.ndarray]  # joint -> (n,) full-lift rotation per note
    scales: dict[int, float]
    bias: float = 0.0  # at the contacts (elsewhere the tension of 1 leaves no tangent)

    def curves(self) -> dict[int, JointCurve]:
        k = self.keys
        tension = np.where(k.kind == CONTACT, 0.0, 1.0)
        continuity = np.where(k.kind == CONTACT, -1.0, 0.0)
        bias = np.where(k.kind == CONTACT, self.bias, 0.0) if self.bias else None
        out: dict[int, JointCurve] = {}
        every = np.arange(k.time_s.size)
        for j in self.base:
            rv = self.rotvecs(j, every)
            out[j] = JointCurve(lagged_times(k, self.scales[j]), rv, tension, continuity, bias)
        return out

    def rotvecs(self, j: int, at: np.ndarray) -> np.ndarray:
        """Rotation vectors of joint ``j`` at keys ``at`` (a merged or travel key averages
        the poses of its two notes)."""
        k = self.keys
        rv = []
        for n_idx in (k.note[at], k.note2[at]):
            angle = k.lift[at] * self.amps[j][n_idx] * self.signed[j][n_idx]
            q = quat.mul_x(self.base[j][n_idx], angle)
            rv.append(quat.log(q))
        out: np.ndarray = 0.5 * (rv[0] + rv[1])
        return out

    def set_lift(self, curves: dict[int, JointCurve], at: np.ndarray, lift: np.ndarray) -> None:
        """Change the lift of keys ``at`` and update ``curves`` in place."""
        self.keys.lift[at] = lift
        for j, curve in curves.items():
            curve.rotvec[at] = self.rotvecs(j, at)


#: What the clearance search settled, by key (side, time, kind, lift before the search): the
#: lift it kept and how deep the arcs still dipped with it, so a live caller re-animating an
#: overlapping window need not search again (see animate).
ClearanceMemo = dict[tuple[str, float, int, float], tuple[float, float]]


def _clear_kit(
    anim: Animation,
    arm_keys: dict[str, _ArmKeys],
    step: Callable[[], None],
    memo: ClearanceMemo | None = None,
) -> None:
    """Keep raised sticks out of the kit. A preparation, rebound or merged key whose stick
    (or the arc next to it) dips into a piece, say a loud floor-tom preparation under the
    ride, is lowered step by step; then a travel arc that does is raised, or else lowered.
    Each key keeps its first clear setting (or the shallowest); what is left shows up in the
    penetration check (and is caught by :func:`guard_sticks` when sampling).

    With ``memo``, a key a previous search settled starts from that setting; if its arcs dip
    no deeper than they did then (the one probe every key gets anyway), the setting is kept;
    else the key goes back to its own lift and is searched as usual. The memo is then
    replaced by this call's settings."""
    settled: ClearanceMemo = {}
    for side, arm in arm_keys.items():
        kind = arm.keys.kind
        raised = np.flatnonzero(kind != CONTACT)
        lift0 = arm.keys.lift[raised].copy()
        at_s = np.round(arm.keys.time_s[raised], 6).tolist()
        ids = list(
            zip(
                [side] * raised.size,
                at_s,
                kind[raised].tolist(),
                np.round(lift0, 6).tolist(),
                strict=True,
            )
        )
        old = [memo.get(i) if memo is not None else None for i in ids]
        known = np.array([m is not None for m in old], dtype=bool)
        if known.any():
            arm.set_lift(
                anim.arms[side], raised[known], np.array([m[0] for m in old if m is not None])
            )
        depth = _probe_depth(anim, side, raised)
        was = np.array([m[1] if m is not None else np.inf for m in old])
        kept = known & (depth <= was + GUARD_TOLERANCE_M * 0.2)
        stale = known & ~kept
        if stale.any():  # the remembered setting no longer does: search from scratch
            arm.set_lift(anim.arms[side], raised[stale], lift0[stale])
            depth[stale] = _probe_depth(anim, side, raised[stale])
        bad = (depth > 0.0) & ~kept
        if bad.any():
            free = bad & np.isin(kind[raised], (BEFORE, AFTER, MERGED))
            travel = bad & (kind[raised] == TRAVEL)
            step()
            depth[free] = _search(
                anim, side, arm, raised[free], depth[free], TRIES_SCALE, True, step
            )
            depth[travel] = _search(
                anim, side, arm, raised[travel], depth[travel], TRIES_TRAVEL, False, step
            )
        final = arm.keys.lift[raised]
        for k in np.flatnonzero(bad | kept).tolist():
            settled[ids[k]] = (float(final[k]), float(depth[k]))
    if memo is not None:
        memo.clear()
        memo.update(settled)


def _probe_depth(anim: Animation, side: str, at: np.ndarray) -> np.ndarray:
    """Deepest penetration of the stick tip on the arcs on either side of keys ``at``."""
    if at.size == 0:
        return np.zeros(0)
    times = anim.arms[side][ARM[side.upper()][0]].time_s  # shoulder keys: the limb's timing
    last = times.size - 1
    lo = times[np.maximum(at - 1, 0)]
    hi = times[np.minimum(at + 1, last)]
    frac = np.linspace(0.0, 1.0, 2 * PROBES + 1)[1:]
    t = (lo[:, None] + (hi - lo)[:, None] * frac[None, :]).ravel()
    depth = penetration_depth(anim.rig.surfaces, arm_tip(anim, side, t))
    out: np.ndarray = depth.reshape(at.size, -1).max(-1)
    return out


def arm_tip(anim: Animation, side: str, times: np.ndarray) -> np.ndarray:
    """Stick tip positions (T, 3) of one arm, by the arm's own short chain (no legs, no guard):
    what the clearance search probes thousands of times."""
    skel = anim.rig.skeleton
    _, r_sh, l_sh = _spine(anim.rig, anim.torso, times)
    pos = r_sh if side == "r" else l_sh
    sh_j, el_j, wr_j, st_j, tip_j = ARM[side.upper()]
    curves = anim.arms[side]
    q = curves[sh_j].sample(times)  # world, see PARENT_IS_CHEST
    for j, child in ((sh_j, el_j), (el_j, wr_j), (wr_j, st_j), (st_j, tip_j)):
        if j != sh_j:
            q = quat.mul(q, curves[j].sample(times))
        pos = pos + quat.rotate(q, skel.offsets[child])
    return pos


def _search(
    anim: Animation,
    side: str,
    arm: _ArmKeys,
    keys: np.ndarray,
    depth: np.ndarray,
    tries: tuple[float, ...],
    scale: bool,
    step: Callable[[], None],
) -> np.ndarray:
    """Try lift settings for ``keys`` (whose current arcs dip ``depth`` into the kit), keeping
    per key the first that clears the kit, else the shallowest; returns how deep each still
    dips with the setting kept."""
    if keys.size == 0:
        return depth
    curves = anim.arms[side]
    start = arm.keys.lift[keys].copy()
    best_lift = start.copy()
    best_depth = depth.copy()
    todo = np.arange(keys.size)
    for value in tries:
        at = keys[todo]
        trial = np.maximum(start[todo] * value if scale else start[todo] + value, 0.0)
        arm.set_lift(curves, at, trial)
        depth = _probe_depth(anim, side, at)
        better = depth < best_depth[todo]
        best_depth[todo[better]] = depth[better]
        best_lift[todo[better]] = trial[better]
        todo = np.flatnonzero(best_depth > 0.0)
        step()
        if todo.size == 0:
            break
    arm.set_lift(curves, keys, best_lift)
    return best_depth
