"""The result every limb-assignment strategy returns, and what strokes and checks consume.

One row per input onset, in the input's time order, so callers index the onset array and the
limb array with the same integer. ``limb`` holds indices into :data:`LIMBS`, or
:data:`NOT_PLAYED` for a note no limb plays (each such note has its reason in ``reasons``;
nothing is lost silently). ``piece`` is the index into ``kit.pieces`` of the piece that sounds
(-1 when the kit has no piece for the instrument). A note the hands cannot strike as a
stroke of its own (a third hand note of a chord, a second stroke on one hi-hat) is *merged*: it
has the limb of the stroke it joins (a flam or double stroke of that hand) and a reason that
starts with :data:`MERGED` (:func:`merged_notes`). ``onsets`` is the input after any
substitution a drummer would make (a hi-hat stroke played with the pedal has zone ``pedal``);
every substituted onset also has a reason.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from livedrummer.kit.vocabulary import Limb

LIMBS: tuple[Limb, ...] = (Limb.RH, Limb.LH, Limb.RF, Limb.LF)
LIMB_CODE: dict[Limb, int] = {limb: i for i, limb in enumerate(LIMBS)}
NOT_PLAYED = -1
#: How the reason of a merged note starts (see the module docstring).
MERGED = "merged:"


@dataclass(frozen=True)
class Sticking:
    """Limb and piece per onset (see the module docstring)."""

    onsets: np.ndarray  # ONSET_DTYPE
    limb: np.ndarray  # int8, index into LIMBS or NOT_PLAYED
    piece: np.ndarray  # int16, index into kit.pieces or -1
    reasons: Mapping[int, str]  # onset index -> why it was substituted or not played
    strategy: str
    kit_name: str

    def limb_of(self, i: int) -> Limb | None:
        code = int(self.limb[i])
        return None if code == NOT_PLAYED else LIMBS[code]


def merged_notes(sticking: Sticking) -> np.ndarray:
    """True for every note merged into another's stroke (see the module docstring)."""
    out = np.zeros(sticking.limb.size, dtype=bool)
    for i, why in sticking.reasons.items():
        out[i] = why.startswith(MERGED)
    return out
