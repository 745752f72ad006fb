"""The sticking sheet: limbs over the score, bar by bar and beat by beat, as a teacher writes it.

Pure string building from a :class:`~.result.Sticking` and the piece's beat grid. Each line
is one grid position (``2``, ``2e``, ``2&``, ``2a`` for sixteenths within 0.09 beat, ``2t``
and ``2l`` for the triplet's "trip" and "let"; any other position shows its beat fraction, such
as ``2.40``), listing every note there as ``piece LIMB`` with the limb as a teacher writes it
(``R``, ``L``, ``RF``, ``LF``); a note nobody plays shows ``--`` and its reason is listed after
the bar. A stroke too hard to play (too fast for one hand, or with the arms crossed; see
:func:`~.metrics.hard_notes`) carries a ``!`` after its limb and is explained after the bar, as
SMED showed the parts of a score too hard to play; a last line counts them.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking.metrics import hard_notes
from livedrummer.sticking.prepare import beat_position
from livedrummer.sticking.result import LIMBS, NOT_PLAYED, Sticking

_SHORT = {Limb.RH: "R", Limb.LH: "L", Limb.RF: "RF", Limb.LF: "LF"}
_SIXTEENTH = ("", "e", "&", "a")
_TRIPLET = ("", "t", "l")  # "1 trip let"
_TOL = 0.09  # beats: how far a played note may sit from its grid position


def _label(beat_in_bar: int, frac: float) -> str:
    beat = beat_in_bar + 1
    k = round(frac * 4)
    if abs(frac - k / 4) < _TOL and k < 4:
        return f"{beat}{_SIXTEENTH[k]}"
    k = round(frac * 3)
    if abs(frac - k / 3) < _TOL and 0 < k < 3:
        return f"{beat}{_TRIPLET[k]}"
    return f"{beat + frac:.2f}"


def render_sheet(
    sticking: Sticking, kit: Kit, beat_s: np.ndarray, bar: np.ndarray, beat_in_bar: np.ndarray
) -> str:
    """The sheet text (see the module docstring)."""
    on = sticking.onsets
    if on.size == 0:
        return "(no notes)\n"
    if beat_s.size < 2:
        beat_s = np.array([0.0, 0.5])
        bar, beat_in_bar = np.zeros(2, np.int32), np.arange(2, dtype=np.int16)
    pos = beat_position(on["time_s"], beat_s)
    hard = hard_notes(sticking, kit)
    lines: list[str] = []
    current_bar = -1
    notes_for_bar: list[str] = []
    row_key: tuple[int, str] | None = None
    row: list[str] = []

    def flush_row() -> None:
        if row_key is not None and row:
            lines.append(f"  {row_key[1]:<6} " + "  ".join(row))
        row.clear()

    for i in range(on.size):
        b = int(np.clip(np.floor(pos[i] + _TOL), 0, beat_s.size - 1))
        frac = max(0.0, float(pos[i] - b))
        bar_i = int(bar[b]) if b < bar.size else int(bar[-1])
        label = _label(int(beat_in_bar[b]) if b < beat_in_bar.size else 0, frac)
        if bar_i != current_bar:
            flush_row()
            lines.extend(notes_for_bar)
            notes_for_bar = []
            lines.append(f"bar {bar_i + 1}")
            current_bar = bar_i
            row_key = None
        if row_key != (b, label):
            flush_row()
            row_key = (b, label)
        p = int(sticking.piece[i])
        piece = kit.pieces[p].name if p >= 0 else f"note{int(on['note'][i])}"
        code = int(sticking.limb[i])
        limb = _SHORT[LIMBS[code]] if code != NOT_PLAYED else "--"
        row.append(f"{piece} {limb}{'!' if i in hard else ''}")
        if i in sticking.reasons:
            notes_for_bar.append(f"    * {label} {piece}: {sticking.reasons[i]}")
        if i in hard:
            notes_for_bar.append(f"    ! {label} {piece} {limb}: {hard[i]}")
    flush_row()
    lines.extend(notes_for_bar)
    if hard:
        lines.append(f"too hard to play (!): {len(hard)} of {on.size} notes")
    return "\n".join(lines) + "\n"
