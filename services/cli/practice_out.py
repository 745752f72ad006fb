"""Writing the practice reports (:mod:`livedrummer.practice.report`) for ``practice`` commands.

The reference's sticking (who should play each note) comes from the one entry point every
command uses, :func:`~livedrummer.sticking.strategy.stick_performance`, on the default kit
with the default strategy; its bars and tempo from the reference's grid.
The page is written to ``NAME.part`` and renamed once whole, so a reader never sees half a
report.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.errors import LivedrummerError
from livedrummer.practice.match import Matching
from livedrummer.practice.plan import Segment, pass_index
from livedrummer.timeline.performance import Performance

REPORT_KIT = "rock5"


def bars_of(performance: Performance, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(bar index of each time, reference tempo in bpm of each bar) from the grid."""
    grid = performance.grid
    if grid.beat_s.size < 2:
        return np.zeros(times_s.size, dtype=np.int64), np.full(1, 120.0)
    idx = np.clip(np.searchsorted(grid.beat_s, times_s, side="right") - 1, 0, None)
    bar_of = grid.bar[idx].astype(np.int64)
    gaps = np.diff(grid.beat_s)
    gap_bar = grid.bar[:-1]
    bars = int(grid.bar[-1]) + 1
    bpm = np.full(bars, 60.0 / float(np.median(gaps)))
    for b in range(bars):
        pick = gaps[gap_bar == b]
        if pick.size:
            bpm[b] = 60.0 / float(pick.mean())
    return bar_of, bpm


def write_take_report(
    path: Path,
    result: dict[str, Any],
    reference: Performance,
    matching: Matching,
    seg: Segment | None = None,
    scale: float = 1.0,
) -> None:
    """The take's report; ``seg`` and ``scale``: the pass the take was judged against (its
    notes' times are on the pass clock; see :mod:`livedrummer.practice.plan`)."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.practice.report import take_report
    from livedrummer.sticking.strategy import stick_performance

    sticking = stick_performance(reference, load_kit(REPORT_KIT))
    ref_i = matching.notes["ref"]
    ref_t = matching.notes["time_s"]
    if seg is not None:
        ref_i = pass_index(reference.onsets, seg)[ref_i]
        ref_t = seg.start_s + ref_t * scale
    limbs = [sticking.limb_of(int(i)) for i in ref_i.tolist()]
    names = [None if limb is None else limb.value for limb in limbs]
    bar_of, bpm = bars_of(reference, ref_t)
    bpm = bpm * scale
    _write(path, take_report(result, matching.notes, names, bar_of, bpm))


def write_history_report(path: Path, sessions: list[dict[str, Any]]) -> None:
    from livedrummer.practice.report import history_report

    _write(path, history_report(sessions))


def _write(path: Path, text: str) -> None:
    part = path.with_name(path.name + ".part")
    try:
        part.write_text(text, encoding="utf-8")
        part.replace(path)
    except OSError as exc:
        raise LivedrummerError(f"{path}: cannot write the report: {exc.strerror or exc}") from None
