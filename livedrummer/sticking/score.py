"""The text sticking score: one line per note, written by the CLI, edited by hand, read back.

SMED kept its scores as text so that users could correct hand assignments; this is the same
idea for MIDI files. ``livedrummer sticking FILE.mid --format text`` writes::

    # livedrummer sticking score 1
    # kit rock5, map general-midi, strategy optimal
    # time_s      note  piece     limb  reason
    0.000000       36   kick      RF
    0.000000       42   hihat     RH
    0.250000       38   snare     LH

Change a ``limb`` (``RH``, ``LH``, ``RF``, ``LF``; ``R``/``L`` also accepted; ``-`` leaves the
note out; ``?`` lets the strategy decide) and pass the file back with ``--score FILE``: every
limb written is the limb played, and the strategy fits the other notes around it. Lines are
matched to the MIDI file's notes by time (to a microsecond) and note number, so the file
must come from the same MIDI file and note map; a line that matches no note is an error naming
its line. Everything after the limb (the reason column) and every ``#`` comment is ignored.
"""

from __future__ import annotations

from collections import defaultdict, deque
from pathlib import Path

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb
from livedrummer.sticking.prepare import UNANNOTATED
from livedrummer.sticking.result import LIMB_CODE, LIMBS, NOT_PLAYED, Sticking
from livedrummer.sticking.tab import ScoreError

HEADER = "# livedrummer sticking score 1"
_TOKENS = {limb.value: LIMB_CODE[limb] for limb in Limb} | {
    "R": LIMB_CODE[Limb.RH],
    "L": LIMB_CODE[Limb.LH],
    "-": NOT_PLAYED,
    "?": UNANNOTATED,
}


def _key(time_s: float, note: int) -> tuple[int, int]:
    return round(time_s * 1e6), note


def write_score(sticking: Sticking, kit: Kit, map_name: str = "") -> str:
    """The score text of a sticking (see the module docstring)."""
    lines = [
        HEADER,
        f"# kit {kit.name}, map {map_name or '?'}, strategy {sticking.strategy}",
        "# edit the limb column (RH LH RF LF, - to leave out, ? to let the strategy decide)",
        "# time_s      note  piece     limb  reason",
    ]
    on = sticking.onsets
    for i in range(on.size):
        p = int(sticking.piece[i])
        piece = kit.pieces[p].name if p >= 0 else "-"
        code = int(sticking.limb[i])
        limb = LIMBS[code].value if code != NOT_PLAYED else "-"
        reason = sticking.reasons.get(i, "")
        line = (
            f"{float(on['time_s'][i]):.6f}  {int(on['note'][i]):>6}   {piece:<9} {limb:<5} {reason}"
        )
        lines.append(line.rstrip())
    return "\n".join(lines) + "\n"


def read_score(text: str, onsets: np.ndarray, source: str = "<score>") -> np.ndarray:
    """Explicit limbs per onset (int8; UNANNOTATED where the score leaves it open)."""
    slots: dict[tuple[int, int], deque[int]] = defaultdict(deque)
    for i, (t, note) in enumerate(
        zip(onsets["time_s"].tolist(), onsets["note"].tolist(), strict=True)
    ):
        slots[_key(t, note)].append(i)
    out = np.full(onsets.size, UNANNOTATED, dtype=np.int8)
    for lineno, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = line.split()
        where = f"{source}:{lineno}"
        if len(fields) < 4:
            raise ScoreError(f"{where}: expected 'time_s note piece limb', got {raw.strip()!r}")
        try:
            key = _key(float(fields[0]), int(fields[1]))
        except ValueError:
            raise ScoreError(f"{where}: bad time or note in {raw.strip()!r}") from None
        if fields[3] not in _TOKENS:
            raise ScoreError(f"{where}: limb {fields[3]!r} is not one of {' '.join(_TOKENS)}")
        queue = next((q for k in (0, -1, 1) if (q := slots.get((key[0] + k, key[1])))), None)
        if not queue:
            raise ScoreError(f"{where}: no note {fields[1]} at {fields[0]} s in the MIDI file")
        out[queue.popleft()] = _TOKENS[fields[3]]
    return out


def read_score_file(path: Path, onsets: np.ndarray) -> np.ndarray:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ScoreError(f"{path}: cannot read the sticking score: {exc.strerror}") from None
    return read_score(text, onsets, str(path))
