"""Strategies by name, and the one front door every caller uses: :func:`assign`.

Every strategy takes the same input (an onset record array and a kit, optionally the beat grid)
and returns a :class:`~.result.Sticking`, so the CLI, the benchmark and the body can switch
between them by name. :func:`assign` also applies a score's explicit limbs (see :mod:`.score`):
``optimal`` fits its search around them; the seed strategies, which cannot, have their result
overridden note by note. Either way, a limb written in the score is the limb played.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Protocol

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.kit import Kit
from livedrummer.sticking.kragtwijk import kragtwijk_basic, kragtwijk_pair
from livedrummer.sticking.optimal import optimal
from livedrummer.sticking.prepare import UNANNOTATED, apply_explicit, route
from livedrummer.sticking.result import NOT_PLAYED, Sticking
from livedrummer.sticking.smed import smed


class StrategyError(LivedrummerError):
    """An unknown strategy name."""


class Strategy(Protocol):
    def __call__(
        self, onsets: np.ndarray, kit: Kit, *, beat_s: np.ndarray | None = None
    ) -> Sticking: ...


STRATEGIES: MappingProxyType[str, Strategy] = MappingProxyType(
    {
        "optimal": optimal,
        "kragtwijk-basic": kragtwijk_basic,
        "kragtwijk-pair": kragtwijk_pair,
        "smed": smed,
    }
)
DEFAULT_STRATEGY = "optimal"


def get_strategy(name: str) -> Strategy:
    try:
        return STRATEGIES[name]
    except KeyError:
        known = ", ".join(STRATEGIES)
        raise StrategyError(f"unknown sticking strategy {name!r}; known: {known}") from None


def assign(
    onsets: np.ndarray,
    kit: Kit,
    strategy: str = DEFAULT_STRATEGY,
    *,
    beat_s: np.ndarray | None = None,
    explicit: np.ndarray | None = None,
) -> Sticking:
    """Sticking of ``onsets`` on ``kit`` by the named strategy, honouring ``explicit`` limbs."""
    func = get_strategy(strategy)
    if explicit is not None and func is optimal:
        return optimal(onsets, kit, beat_s=beat_s, explicit=explicit)
    result = func(onsets, kit, beat_s=beat_s)
    if explicit is None:
        return result
    return override(result, explicit, kit)


def override(result: Sticking, explicit: np.ndarray, kit: Kit) -> Sticking:
    """``result`` with every annotated note's limb replaced by the annotation."""
    routed = route(result.onsets, kit)
    limb = result.limb.copy()
    onsets = result.onsets.copy()
    reasons = dict(result.reasons)
    why = apply_explicit(routed, explicit, kit)
    marked = (explicit != UNANNOTATED) & (result.piece >= 0)
    limb[marked] = explicit[marked]
    for i in np.flatnonzero(marked).tolist():
        reasons.pop(i, None)
        if i in why:
            reasons[i] = why[i]
            onsets[i] = routed.onsets[i]
        elif explicit[i] == NOT_PLAYED:
            reasons[i] = "left out, as the score says"
    return Sticking(onsets, limb, result.piece, reasons, result.strategy, result.kit_name)
