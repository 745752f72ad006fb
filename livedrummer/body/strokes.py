"""Stroke keyframes per limb: preparation / strike / rebound (SMED) = before / contact / after
(virtual-drummer paper), with both seeds' overlap rules.

A limb's notes become keys carrying a *lift* λ: 0 is the contact pose, 1 the full
preparation of a loud stroke. The body turns λ into joint rotations (each joint turned about
its stroke axis by λ times its amplitude, see :mod:`livedrummer.body.animation`), so this
module is pure timing and amplitude, shared by hands and feet:

* before: λ = velocity (the paper's ``DOWN + vel * diff``: preparation height from velocity),
  at ``contact - δ/2``; contact: λ = 0 at the onset; after: λ = velocity * elasticity at
  ``contact + δ/2`` (elasticity 0 gives after = contact).
* Two notes closer than δ overlap. Same piece and zone (the paper; every pair under the
  ``smed`` model): the after of the first and the before of the second become one key at the
  midpoint whose λ shrinks in proportion to the gap (nearer the DOWN pose the closer the
  notes: SMED's attenuation, figure 4.10). Different pieces: the two keys stay but move
  towards their contacts so that travel between them takes the fraction ``a`` of the gap;
  their λ also shrinks with the gap, but not below ``travel_lift``, and a *travel* key
  halfway between them lifts the stick over whatever lies between the two pieces (this
  arc is ours; the seeds interpolate straight between the poses).

Models: ``livedrummer`` (default: all of the above), ``paper`` (no attenuation, no travel
floor or arc), ``smed`` (every overlap merges and attenuates). Keys come out sorted with their
*anchor* (the contact they belong to), which the body uses for the whip-like lag of stick
behind wrist behind elbow: lagging joints keep their contacts and move their before/after
keys closer to them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MODELS = ("livedrummer", "paper", "smed")

BEFORE, CONTACT, AFTER, MERGED, TRAVEL = 0, 1, 2, 3, 4


@dataclass(frozen=True, slots=True)
class StrokeParams:
    delta_s: float = 0.10  # the paper's δ: before and after keys lie δ/2 from the contact
    fraction_a: float = 0.5  # share of a short gap spent travelling between pieces
    model: str = "livedrummer"
    travel_lift: float = 0.3  # least λ of keys between two different pieces
    travel_raise: float = 0.25  # extra λ of the arc between two different pieces
    lag: float = 0.2  # whip: wrist keys at (1 - lag), stick at (1 - 2 lag) of the offsets
    full_amplitude_rad: float = 1.3  # total preparation rotation at velocity 127, gain 1

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise ValueError(f"stroke model must be one of {MODELS}, got {self.model!r}")
        if not 0.0 < self.fraction_a < 1.0:
            raise ValueError(f"fraction a must be in (0, 1), got {self.fraction_a}")


@dataclass(frozen=True)
class Keys:
    """Keys of one limb, sorted by time."""

    time_s: np.ndarray  # (K,)
    lift: np.ndarray  # (K,) λ
    kind: np.ndarray  # (K,) BEFORE, CONTACT, AFTER or MERGED
    note: np.ndarray  # (K,) index of the note whose contact pose is the base
    note2: np.ndarray  # (K,) second base note (merged keys), else == note
    anchor_s: np.ndarray  # (K,) contact time the key belongs to (its own time if merged)


def stroke_keys(
    time_s: np.ndarray,
    target_id: np.ndarray,
    velocity: np.ndarray,
    elasticity: np.ndarray,
    params: StrokeParams,
    piece_id: np.ndarray | None = None,
) -> Keys:
    """Keys for one limb's notes (sorted times; velocity in 0..1; target_id equal for the same
    piece and zone; piece_id, if given, adds a travel key between different pieces)."""
    n = time_s.size
    if n == 0:
        e = np.zeros(0)
        ei = np.zeros(0, dtype=np.int64)
        return Keys(e, e, ei, ei, ei, e)
    half = 0.5 * params.delta_s
    gap = np.diff(time_s)
    overlap = gap < params.delta_s
    same = target_id[:-1] == target_id[1:]
    merge = overlap & (same | (params.model == "smed"))
    shorten = overlap & ~merge
    closeness = np.clip(gap / params.delta_s, 0.0, 1.0)

    before_t = time_s - half
    after_t = time_s + half
    before_l = velocity.astype(np.float64).copy()
    after_l = velocity * elasticity
    squeeze = (1.0 - params.fraction_a) * gap / 2.0
    after_t[:-1] = np.where(shorten, time_s[:-1] + squeeze, after_t[:-1])
    before_t[1:] = np.where(shorten, time_s[1:] - squeeze, before_t[1:])
    if params.model != "paper":
        floor = params.travel_lift
        after_l[:-1] = np.where(shorten, np.maximum(after_l[:-1] * closeness, floor), after_l[:-1])
        before_l[1:] = np.where(shorten, np.maximum(before_l[1:] * closeness, floor), before_l[1:])
    merged_l = 0.5 * (after_l[:-1] + before_l[1:]) * closeness

    idx = np.arange(n)
    travel = np.zeros(n - 1, dtype=bool)
    if piece_id is not None and params.model != "paper":
        travel = ~merge & (piece_id[:-1] != piece_id[1:])
    tr = np.flatnonzero(travel)
    travel_l = (
        np.maximum(np.maximum(after_l[:-1], before_l[1:]), params.travel_lift)
        + params.travel_raise * closeness
    )[tr]
    travel_t = 0.5 * (after_t[:-1] + before_t[1:])[tr]
    keep_after = np.ones(n, dtype=bool)
    keep_before = np.ones(n, dtype=bool)
    keep_after[:-1] = ~merge
    keep_before[1:] = ~merge
    m = np.flatnonzero(merge)
    parts = [
        (
            before_t[keep_before],
            before_l[keep_before],
            BEFORE,
            idx[keep_before],
            idx[keep_before],
            time_s[keep_before],
        ),
        (time_s, np.zeros(n), CONTACT, idx, idx, time_s),
        (
            after_t[keep_after],
            after_l[keep_after],
            AFTER,
            idx[keep_after],
            idx[keep_after],
            time_s[keep_after],
        ),
        (time_s[m] + 0.5 * gap[m], merged_l[m], MERGED, m, m + 1, time_s[m] + 0.5 * gap[m]),
        (travel_t, travel_l, TRAVEL, tr, tr + 1, travel_t),
    ]
    t = np.concatenate([p[0] for p in parts])
    lift = np.concatenate([p[1] for p in parts])
    kind = np.concatenate([np.full(p[0].size, p[2]) for p in parts])
    note = np.concatenate([p[3] for p in parts])
    note2 = np.concatenate([p[4] for p in parts])
    anchor = np.concatenate([p[5] for p in parts])
    # ties (a before key exactly at the previous after) keep the stroke order
    rank = np.array([0, 1, 2, 2, 3])[kind]
    order = np.lexsort((rank, note, t))
    return Keys(t[order], lift[order], kind[order], note[order], note2[order], anchor[order])


def lagged_times(keys: Keys, scale: float) -> np.ndarray:
    """Key times for a joint whose before/after keys sit ``scale`` (<= 1) as far from their
    contact as the limb's: the joint arrives later and leaves sooner (whip lag, frequency)."""
    own = (keys.kind == BEFORE) | (keys.kind == AFTER)
    return np.where(own, keys.anchor_s + scale * (keys.time_s - keys.anchor_s), keys.time_s)
