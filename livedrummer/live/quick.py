"""Quick contacts: every arriving hit's contact pose, sent within a millisecond.

The synthesizer's curves are rebuilt (10-20 ms) whenever its window of notes changes. A hit
need not wait for that to be shown striking: its contact pose is the current pose at the
onset with one limb moved onto the struck piece, and that is one inverse-kinematics solve.
:func:`quick_contact` takes a :class:`QuickState` (what
:meth:`~livedrummer.live.synth.LiveSynth.quick_state` copies out of the synthesizer: the
samples it published lately and holds ahead, its curves for a time no sample is near, the
quick contacts it sent that the curves do not have yet) and the onsets that just arrived
with the limbs the synthesizer gives them (decided, or provisional), and returns one pose
record per onset time, to show at onset + D:

* the body as sampled nearest the onset (torso, head, the other limbs), or the quick contact
  already sent for that time (a chord whose notes came in two messages);
* each striking arm solved by :func:`~livedrummer.body.ik.solve_arm` from that sample's own
  shoulder and chest, so the stick tip lies on the target exactly (a foot: the leg solved
  onto its footboard, the beater or footboard on its contact angle);
* the struck piece's channels as at a hit: full glow at the velocity, a cymbal's wobble
  restarting from zero.

The whole batch is solved at once (one IK call per limb), so a burst of notes that arrived
together costs what one does. Nothing in the state is changed. The re-animated curves
replace these samples a moment later with the whole stroke (the same contact when the
provisional limb was right: both are the same IK onto the same point)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from livedrummer.body import quat
from livedrummer.body.animation import Animation
from livedrummer.body.ik import solve_arm, solve_leg
from livedrummer.body.rig import Rig
from livedrummer.body.sample import sample_poses
from livedrummer.body.skeleton import ARM, LEG, J
from livedrummer.sticking.result import Sticking
from livedrummer.vocabulary import ZONES, PieceKind, Zone

#: a published or held sample this close to the onset stands for the body at the onset
NEAR_S = 0.02
_PEDAL = ZONES.index(Zone.PEDAL)


@dataclass
class Curves:
    """One animation of the synthesizer's window, and what it was built from."""

    anim: Animation
    sticking: Sticking
    key: tuple[object, ...]
    contacts_s: np.ndarray  # committed contacts (performance time), sorted


@dataclass(frozen=True)
class QuickState:
    """A read-only copy of what :func:`quick_contact` needs (see the module docstring)."""

    rig: Rig
    dtype: np.dtype
    curves: Curves | None
    old: Curves | None  # the curves being faded out, with the fade (start, length)
    fade: tuple[float, float]
    samples_t: np.ndarray  # performance times of samples published lately and held ahead
    samples: np.ndarray  # their pose records
    struck: dict[float, np.ndarray]  # quick contacts not yet in the curves, by onset time


def sample_curves(
    curves: Curves,
    old: Curves | None,
    fade: tuple[float, float],
    times: np.ndarray,
    pause: Callable[[], None] | None = None,
) -> tuple[np.ndarray, bool]:
    """Pose records at ``times``, cross-faded from ``old`` over ``fade``; and whether the fade
    is over for all of them (then ``old`` can be dropped). ``pause``: called between the two
    samplings (see :func:`~livedrummer.body.animation.animate`)."""
    rows = sample_poses(curves.anim, curves.sticking, times)
    if old is None:
        return rows, True
    f0, flen = fade
    w = np.clip((times - f0) / flen, 0.0, 1.0) if flen > 0 else np.ones_like(times)
    fading = w < 1.0
    if not fading.any():
        return rows, True
    if pause is not None:
        pause()
    prev = sample_poses(old.anim, old.sticking, times[fading])
    blend_rows(prev, rows[fading], w[fading])
    rows[fading] = prev
    return rows, False


def blend_rows(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> None:
    """``a`` becomes ``(1 - w) a + w b`` in place: positions and channels linearly, rotations
    by normalised linear interpolation on the same hemisphere."""
    wc = w.astype(np.float32)
    for name in ("position", "swing", "lift", "glow"):
        shape = (-1,) + (1,) * (a[name].ndim - 1)
        a[name] = a[name] + (b[name] - a[name]) * wc.reshape(shape)
    qa, qb = a["rotation"], b["rotation"].copy()
    flip = np.sum(qa * qb, axis=-1) < 0
    qb[flip] *= -1.0
    q = qa + (qb - qa) * wc[:, None, None]
    a["rotation"] = q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), 1e-12)


def quick_contact(
    state: QuickState,
    rows: np.ndarray | np.void,
    limbs: np.ndarray | int,
    pieces: np.ndarray | int,
) -> tuple[np.ndarray, np.ndarray]:
    """Onset times and pose records to send at once (shown at onset + D) for onsets ``rows``
    (ONSET_DTYPE), played by ``limbs`` (0-3: right hand, left hand, right foot, left foot;
    -1: not played) on kit pieces ``pieces``: one record per distinct onset time, ascending
    (the limbs of a chord strike together in it); empty when there is nothing to start from
    yet (see the module docstring). One IK solve per limb for the whole batch: a burst costs
    what a hit does."""
    rows = np.atleast_1d(np.asarray(rows))
    limbs, pieces = np.atleast_1d(limbs), np.atleast_1d(pieces)
    play = (limbs >= 0) & (pieces >= 0)
    if not play.any():
        return np.zeros(0), np.zeros(0, state.dtype)
    times, at = np.unique(rows["time_s"][play].astype(np.float64), return_inverse=True)
    base = _bodies_at(state, times)
    if base is None:
        return np.zeros(0), np.zeros(0, state.dtype)
    hits, limb, piece = rows[play], limbs[play], pieces[play]
    for code in range(4):
        sel = np.flatnonzero(limb == code)
        # a limb given two notes at one time: the last one is drawn
        _, last = np.unique(at[sel][::-1], return_index=True)
        sel = sel[::-1][last]
        if sel.size:
            h = hits[sel]
            base[at[sel]] = strike_poses(
                state.rig, base[at[sel]], code, piece[sel].astype(np.int64),
                h["zone"].astype(np.int64), h["velocity"], h["openness"],
            )  # fmt: skip
    return times, base


def _bodies_at(state: QuickState, times: np.ndarray) -> np.ndarray | None:
    """The body at each of ``times``: the quick contact already sent for that time (a chord
    completed), else the published or held sample nearest it, else sampled from the curves."""
    out = np.zeros(times.size, state.dtype)
    todo = np.ones(times.size, dtype=bool)
    for k, t in enumerate(times.tolist()):
        if t in state.struck:
            out[k], todo[k] = state.struck[t], False
    if todo.any() and state.samples_t.size:
        i = np.clip(np.searchsorted(state.samples_t, times), 1, state.samples_t.size - 1)
        i = np.where(np.abs(state.samples_t[i - 1] - times) < np.abs(state.samples_t[i] - times),
                     i - 1, i) if state.samples_t.size > 1 else np.zeros_like(i)  # fmt: skip
        near = todo & (np.abs(state.samples_t[i] - times) <= NEAR_S)
        out[near], todo[near] = state.samples[i[near]], False
    if todo.any():
        if state.curves is None:
            return None
        out[todo], _ = sample_curves(state.curves, state.old, state.fade, times[todo])
    return out


def strike_poses(rig: Rig, base: np.ndarray, limb: int, piece: np.ndarray, zone: np.ndarray,
                 velocity: np.ndarray, openness: np.ndarray) -> np.ndarray:  # fmt: skip
    """``base`` (N pose records) with ``limb`` on (``piece``, ``zone``) at contact, each."""
    rec = base.copy()
    rot, pos = rec["rotation"], rec["position"]
    n = rec.size
    if limb in (0, 1):
        side = "R" if limb == 0 else "L"
        sh_j, el_j, wr_j, st_j, tip_j = ARM[side]
        chest_w = quat.mul(rot[:, J["lower_back"]].astype(np.float64),
                           rot[:, J["chest"]].astype(np.float64))  # fmt: skip
        point, normal, pitch = rig.targets.lookup(piece, zone, openness)
        shoulder = pos[:, sh_j].astype(np.float64)
        sign = 1.0 if limb == 0 else -1.0
        sol = solve_arm(rig.skeleton.lengths, shoulder, chest_w, sign, point, normal, pitch)
        rot[:, sh_j] = quat.mul(quat.conj(chest_w), sol.shoulder_q)
        rot[:, el_j] = quat.mul(quat.conj(sol.shoulder_q), sol.elbow_q)
        rot[:, wr_j] = quat.mul(quat.conj(sol.elbow_q), sol.wrist_q)
        rot[:, st_j] = quat.mul(quat.conj(sol.wrist_q), sol.stick_q)
        for j, v in ((el_j, sol.elbow), (wr_j, sol.wrist), (st_j, sol.fulcrum), (tip_j, sol.tip)):
            pos[:, j] = v
    else:
        side = "R" if limb == 2 else "L"
        hip_j, knee_j, ankle_j, toe_j = LEG[side]
        skel = rig.skeleton
        hip = np.broadcast_to(skel.root_m + skel.offsets[hip_j], (n, 3))
        toe = np.array([_footboard(rig, int(k)) for k in piece.tolist()]).reshape(n, 3)
        leg = solve_leg(skel.lengths, hip, toe)
        rot[:, hip_j] = leg.hip_q
        rot[:, knee_j] = quat.mul(quat.conj(leg.hip_q), leg.knee_q)
        rot[:, ankle_j] = quat.mul(quat.conj(leg.knee_q), leg.ankle_q)
        pos[:, knee_j], pos[:, ankle_j], pos[:, toe_j] = leg.knee, leg.ankle, leg.toe
    kinds = [rig.kit.pieces[int(k)].kind for k in piece.tolist()]
    for k, (kind, pc, z, v) in enumerate(zip(kinds, piece.tolist(), zone.tolist(),
                                             velocity.tolist(), strict=True)):  # fmt: skip
        pedal = limb >= 2 and kind in (PieceKind.KICK, PieceKind.HIHAT)
        if pedal or (kind.is_cymbal and kind is not PieceKind.HIHAT):
            rec["swing"][k, pc] = 0.0  # beater on the head, footboard down; wobble restarts
        if not (kind is PieceKind.HIHAT and z == _PEDAL):
            rec["glow"][k, pc] = v / 127.0
    return rec


def _footboard(rig: Rig, piece: int) -> np.ndarray:
    p = rig.kit.pieces[piece]
    return np.asarray(p.pedal_position_m or p.position_m, dtype=np.float64)
