"""Limb assignment: which limb plays each onset, on a given kit.

Front door: :func:`~.strategy.assign` (offline, any strategy by name, honouring a score's
explicit limbs) and :class:`~.online.OnlineSticker` (the optimal strategy on a live stream with
a fixed lookahead). Both return or emit what :class:`~.result.Sticking` holds. How results are
judged is in :mod:`.metrics`; the editable text score is :mod:`.score`, the teacher's drum tab
used by the annotated corpus is :mod:`.tab`, and the readable sheet is :mod:`.sheet`.
"""

from livedrummer.sticking.online import Decision, OnlineSticker, stick_online
from livedrummer.sticking.result import LIMBS, NOT_PLAYED, Sticking
from livedrummer.sticking.strategy import DEFAULT_STRATEGY, STRATEGIES, assign

__all__ = [
    "DEFAULT_STRATEGY",
    "LIMBS",
    "NOT_PLAYED",
    "STRATEGIES",
    "Decision",
    "OnlineSticker",
    "Sticking",
    "assign",
    "stick_online",
]
