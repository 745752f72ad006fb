"""Strategies by name, and the front door every caller uses: :func:`stick_performance`.

Every strategy takes the same input (an onset record array and a kit, optionally the beat grid)
and returns a :class:`~.result.Sticking`, so the CLI, the benchmark and the body can switch
between them by name. :func:`assign` also applies a score's explicit limbs (see :mod:`.score`):
``optimal`` fits its search around them; the seed strategies, which cannot, have their result
overridden note by note. Either way, a limb written in the score is the limb played.

:func:`stick_performance` is the one entry point for a whole performance (a MIDI file, a
replayed session): it takes the beat grid from the performance and reads an edited text score
itself, so no caller can forget either. ``livedrummer sticking`` prints what it returns and
every animating command (render, display, check, export, the offline demo) animates what it
returns, so the sticking sheet and the drummer agree note for note. With ``lookahead_s`` it runs
the online form (:func:`~.online.stick_online`) on the same grid, as a live show would decide.
A live stream, whose notes are not known in advance, uses :class:`~.online.OnlineSticker`
directly (the same recursion, one onset at a time).
"""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Protocol

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.kit.model import Kit
from livedrummer.sticking.kragtwijk import kragtwijk_basic, kragtwijk_pair
from livedrummer.sticking.online import stick_online
from livedrummer.sticking.optimal import optimal
from livedrummer.sticking.prepare import UNANNOTATED, apply_explicit, route
from livedrummer.sticking.result import NOT_PLAYED, Sticking
from livedrummer.sticking.score import read_score_file
from livedrummer.sticking.smed import smed

if TYPE_CHECKING:
    from livedrummer.timeline.performance import Performance


class StrategyError(LivedrummerError):
    """An unknown strategy name, or options of a strategy that do not go together."""


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


def stick_performance(
    performance: Performance,
    kit: Kit,
    strategy: str = DEFAULT_STRATEGY,
    *,
    score: Path | None = None,
    lookahead_s: float | None = None,
) -> Sticking:
    """The sticking of a whole performance on ``kit``: the one every command shows and plays.

    The performance's beat grid always goes to the strategy. ``score`` is an edited text score
    (:mod:`.score`) whose limbs are played as written; ``lookahead_s`` runs the online form of
    ``optimal`` with that lookahead instead (not with a score). Raises :class:`StrategyError`
    for an unknown strategy or options that do not go together, and
    :class:`~.tab.ScoreError` for a score that cannot be read or matched to the notes.
    """
    get_strategy(strategy)
    beat_s = performance.grid.beat_s
    if lookahead_s is not None:
        if strategy != "optimal" or score is not None:
            raise StrategyError("a lookahead runs the optimal strategy, without a score")
        if not lookahead_s >= 0:
            raise StrategyError(f"the lookahead must be >= 0 ms, not {lookahead_s * 1000:g}")
        return stick_online(performance.onsets, kit, lookahead_s, beat_s=beat_s)
    explicit = None if score is None else read_score_file(score, performance.onsets)
    return assign(performance.onsets, kit, strategy, beat_s=beat_s, explicit=explicit)


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
