"""The cost of a hand stroke, from the kit's geometry and a drummer's body, as lookup arrays.

The optimal assigner minimises the sum of these costs over a whole piece, so every habit a
teacher would name has to be a term here, measured from the kit rather than written per drum:

* travel: the distance the stick tip moves between piece centres, dearer the less time there is;
* speed: a stroke sooner than the piece's ``min_time_gap_s`` after the same hand's last one is
  close to impossible (a same-piece double stroke may go to half that gap at a smaller price),
  and one hand repeating below a comfortable pace costs a little, so fills alternate;
* stance: arms crossed beyond the conventional stations (see :mod:`.metrics`), by how far;
* habit: a piece played by the hand the kit does not prefer for it, more so for the hi-hat and
  ride, which a stationed hand keeps; and any other piece on a strong beat played by the
  non-lead hand, so singles lead with the lead hand, as SMED's third pass and method books do.
* triplet groupings: in a run of sixteenth triplets on the drums (the beat grid's
  :data:`~.prepare.BEAT_DTYPE`: consecutive hand notes a sixth of a beat apart, each on that
  grid), the hands go hand to hand, so one hand twice in a row costs ``triplet_double``; the lead
  hand's habit follows the groupings of three (beat, second and third eighth-triplet), not the
  off-beat eighth that the fourth note of the beat falls on; and the hand that leads onto the
  next drum may pass the other one for a stroke, as a drummer's does moving around the toms:
  when the two drums are neighbours (no further apart than a conventional reach) and the other
  hand then meets it on that drum, the pass costs ``triplet_pass`` plus a conventional
  crossing's price per metre (``pass_stance``), not the crossing's full price (the trellis
  charges the full one and gives the difference back at the meeting note, :mod:`.optimal`).

All arrays are indexed by ``kit.pieces`` index and by hand (0 = right, 1 = left). The weights
were tuned on the annotated corpus in ``tests/data/sticking`` (accuracy) and a sample of the
Groove MIDI Dataset (crossings and too-fast strokes: crossing is priced above almost anything,
because a seen crossing is the worst look), and live in one frozen dataclass so a caller can try
others. Limits: no arm model (reach, elbow room), no cymbal height beyond the
conventional-crossing rule, and stroke velocity is ignored.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb, PieceKind
from livedrummer.sticking.metrics import (
    CONVENTIONAL_REACH_M,
    DOUBLE_STROKE_FACTOR,
    STANCE_WINDOW_S,
    crossing_depth,
)
from livedrummer.sticking.prepare import lead_hand

_TIMEKEEPERS = (PieceKind.HIHAT, PieceKind.RIDE)


@dataclass(frozen=True)
class Weights:
    """Cost weights, in "cost units" (a metre of unhurried stick travel costs 1)."""

    move_per_m: float = 1.0  # travel, per metre between piece centres
    move_speed_s: float = 0.05  # extra travel cost per metre, times 1 / interval (s)
    too_fast: float = 6.0  # a stroke below the min gap: this, scaled 1..2 by how far below
    double_stroke: float = 1.2  # a same-piece stroke between half and the full min gap
    comfort: float = 2.5  # one hand repeating: this times (1 - interval / comfortable)^2
    comfort_factor: float = 3.5  # comfortable interval = this times the min gap ...
    timekeeper_comfort_factor: float = 1.3  # ... on the hi-hat and ride, where one hand rides
    cross: float = 30.0  # an unconventional crossing: this times (cross_base + depth in m)
    cross_base: float = 0.4
    cross_conventional: float = 0.3  # a conventional one (hi-hat over snare): per metre
    off_hand: float = 0.5  # a cymbal with the hand the kit does not prefer for it
    off_hand_drum: float = 0.15  # a drum with the hand the kit does not prefer for it
    isolation_s: float = 0.3  # habits count fully for a note this long after the previous one
    off_role: float = 0.7  # added when that cymbal is the hi-hat or ride
    off_lead_on_beat: float = 0.9  # a single note on the beat (half on the "and") off the lead
    triplet_double: float = 5.0  # one hand twice in a row in a sixteenth-triplet run on drums
    triplet_pass: float = 2.5  # ... the leading hand passing the other onto a neighbouring drum


@dataclass(frozen=True)
class CostModel:
    """Everything the dynamic programme needs about a kit, precomputed."""

    weights: Weights
    dist: np.ndarray  # (P, P) metres between piece centres
    min_gap: np.ndarray  # (P,)
    stroke: np.ndarray  # (P, 4, P) [to, row, from]: metres, too-fast limit, min gap, comfort gap
    stance: np.ndarray  # (P, P) [right piece, left piece] cost of the crossing
    bias: np.ndarray  # (2, P) habit cost of playing piece with hand
    beat_bias: np.ndarray  # (2, P) cost per unit of beat strength
    drum: np.ndarray  # (P,) bool: a drum (not a cymbal), where triplet runs are read
    pass_stance: np.ndarray  # (P, P) stance inside a triplet run: neighbours pass cheaply
    home: tuple[int, int]  # where each hand rests before the first note
    lead: int
    stance_window_s: float = STANCE_WINDOW_S
    pieces: int = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "pieces", int(self.min_gap.size))

    @classmethod
    def from_kit(cls, kit: Kit, weights: Weights | None = None) -> CostModel:
        w = weights or Weights()
        pos = np.array([p.position_m for p in kit.pieces])
        dist = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
        gap = np.array([p.min_time_gap_s for p in kit.pieces])
        keeper = np.array([p.kind in _TIMEKEEPERS for p in kit.pieces])
        drum = np.array([not p.kind.is_cymbal for p in kit.pieces])
        comfort = np.where(keeper, w.timekeeper_comfort_factor, w.comfort_factor)
        depth, conventional = crossing_depth(kit)
        stance = np.where(
            conventional, w.cross_conventional * depth, w.cross * (w.cross_base + depth)
        )
        stance = np.where(depth > 0, stance, 0.0)
        neighbours = drum[:, None] & drum[None, :] & (depth <= CONVENTIONAL_REACH_M)
        passing = w.triplet_pass + w.cross_conventional * depth
        pass_stance = np.where(neighbours & (depth > 0), passing, stance)
        lead = 0 if lead_hand(kit) is Limb.RH else 1
        bias = np.zeros((2, len(kit.pieces)))
        beat = np.zeros((2, len(kit.pieces)))
        for i, p in enumerate(kit.pieces):
            pref = p.preferred_limb
            preferred = 0 if pref is Limb.RH else 1 if pref is Limb.LH else lead
            habit = w.off_hand_drum if drum[i] else w.off_hand
            bias[1 - preferred, i] = habit + (w.off_role if keeper[i] else 0.0)
            if not keeper[i]:
                beat[1 - lead, i] = w.off_lead_on_beat
        same = np.eye(len(kit.pieces), dtype=bool)
        gmin = np.maximum(
            np.where(same, gap[:, None], np.minimum(gap[:, None], gap[None, :])), 1e-6
        )
        lim = np.where(same, DOUBLE_STROKE_FACTOR * gmin, gmin)
        stroke = np.stack((dist, lim, gmin, gmin * comfort[:, None]), axis=1)
        return cls(
            w, dist, gap, stroke, stance, bias, beat, drum, pass_stance, _homes(kit, lead), lead
        )


def _homes(kit: Kit, lead: int) -> tuple[int, int]:
    """Resting pieces: each hand's nearest preferred piece (hi-hat and snare on rock5)."""
    homes = []
    for limb in (Limb.RH, Limb.LH):
        mine = [
            i
            for i, p in enumerate(kit.pieces)
            if p.preferred_limb is limb and p.kind is not PieceKind.KICK
        ]
        if not mine:
            mine = [i for i, p in enumerate(kit.pieces) if p.kind is not PieceKind.KICK] or [0]
        homes.append(min(mine, key=lambda i: float(np.hypot(*kit.pieces[i].position_m[:2]))))
    return homes[0], homes[1]
