"""How often is a live upswing visible? The measure behind the synth's prediction goal.

A hand note's upswing is *visible* when, one preparation window before its contact, the live
stick tip is at least ``fraction`` of the offline preparation height above the contact
point, the offline animation (whole performance known, same sticking) being the reference:
the prep height is the tip's height at ``onset - prep_s`` above its height at the onset.
Notes whose offline preparation is lower than ``min_prep_m`` (fast rolls, ghost notes) are
left out: there is no upswing to see. Pure arrays in, a figure out, so the bench and the
tests share it; it lives in ``bench/``, outside the installed package.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Upswing:
    notes: int  # hand notes with a preparation worth measuring
    visible: int

    @property
    def fraction(self) -> float:
        return self.visible / self.notes if self.notes else float("nan")


def upswing_visible(
    offline_prep_z: np.ndarray,
    offline_contact_z: np.ndarray,
    live_prep_z: np.ndarray,
    fraction: float = 0.5,
    min_prep_m: float = 0.02,
) -> Upswing:
    """Per note: tip height (m) one prep window before the onset offline and live, and at the
    contact offline. See the module docstring."""
    off = np.asarray(offline_prep_z) - np.asarray(offline_contact_z)
    live = np.asarray(live_prep_z) - np.asarray(offline_contact_z)
    measured = off >= min_prep_m
    ok = measured & (live >= fraction * off)
    return Upswing(int(measured.sum()), int(ok.sum()))
