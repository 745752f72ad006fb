"""Limb assignment: which limb plays each onset, on a given kit.

Front doors: :func:`~.strategy.stick_performance` for a whole performance (any strategy by
name, the performance's beat grid, an edited text score's limbs; what ``livedrummer sticking``
prints and every animating command plays), :func:`~.strategy.assign` for a bare onset array,
and :class:`~.online.OnlineSticker` (the optimal strategy on a live stream with a fixed
lookahead). All return or emit what :class:`~.result.Sticking` holds. How results are
judged is in :mod:`.metrics`; the editable text score is :mod:`.score`, the teacher's drum tab
used by the annotated corpus is :mod:`.tab`, and the readable sheet is :mod:`.sheet`.
"""

from livedrummer.sticking.online import Decision, OnlineSticker, stick_online
from livedrummer.sticking.result import LIMBS, NOT_PLAYED, Sticking
from livedrummer.sticking.strategy import (
    DEFAULT_STRATEGY,
    STRATEGIES,
    StrategyError,
    assign,
    stick_performance,
)

__all__ = [
    "DEFAULT_STRATEGY",
    "LIMBS",
    "NOT_PLAYED",
    "STRATEGIES",
    "Decision",
    "OnlineSticker",
    "Sticking",
    "StrategyError",
    "assign",
    "stick_online",
    "stick_performance",
]
