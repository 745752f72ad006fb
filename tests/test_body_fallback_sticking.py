"""The stand-in limb assignment the body uses until livedrummer.sticking is wired in."""

from __future__ import annotations

import numpy as np

from livedrummer.body.fallback_sticking import fallback_sticking
from livedrummer.body.rig import build_rig
from livedrummer.events import ONSET_DTYPE
from livedrummer.kitfile import load_kit
from livedrummer.sticking.result import LIMB_CODE, NOT_PLAYED
from livedrummer.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Limb, Zone


def onsets(*notes: tuple[float, str, Zone, HiHat]) -> np.ndarray:
    out = np.zeros(len(notes), dtype=ONSET_DTYPE)
    for i, (t, inst, zone, hat) in enumerate(notes):
        out[i] = (t, 0, 100, 9, INSTRUMENT_CODE[inst], ZONES.index(zone), HIHATS.index(hat),
                  np.nan, 0)  # fmt: skip
    return out


def test_preferred_limbs_alternation_and_unplayable_notes() -> None:
    kit = load_kit("rock5")
    rig = build_rig(kit)
    n = HiHat.NONE
    on = onsets(
        (0.0, "snare", Zone.HEAD, n),  # LH (preferred)
        (0.05, "snare", Zone.HEAD, n),  # too close for the LH: RH takes it
        (0.5, "hihat", Zone.BOW, HiHat.CLOSED),  # RH
        (0.5, "kick", Zone.HEAD, n),  # RF
        (0.5, "hihat", Zone.PEDAL, HiHat.PEDAL),  # LF
        (1.0, "crash1", Zone.EDGE, n),  # RH
        (1.0, "snare", Zone.HEAD, n),  # LH
        (1.0, "tom1", Zone.HEAD, n),  # both hands busy
        (1.0, "cowbell", Zone.HEAD, n),  # no such piece on this kit
    )
    st = fallback_sticking(on, kit, rig.hand_ok)
    names = [p.name for p in kit.pieces]
    code = LIMB_CODE
    assert st.limb.tolist() == [
        code[Limb.LH], code[Limb.RH], code[Limb.RH], code[Limb.RF], code[Limb.LF],
        code[Limb.RH], code[Limb.LH], NOT_PLAYED, NOT_PLAYED,
    ]  # fmt: skip
    assert st.piece[0] == names.index("snare") and st.piece[-1] == -1
    assert st.reasons[7] == "both hands busy" and "cowbell" in st.reasons[8]
    assert set(st.reasons) == {7, 8}
