"""What stops a ringing drum sound besides the next stroke: a cymbal grab and the closing hi-hat.

A grab (polyphonic aftertouch > 0 on a cymbal's note, :data:`~livedrummer.timeline.events.
ControlKind.CHOKE`) stops every stroke of its kit piece at or before it; the body already reads
grabs this way (:func:`~livedrummer.body.sample.kit_choke_times`). The hi-hat pedal closing
(CC4 going from open to closed, :data:`CLOSED_AT` openness or less through the note map's
:meth:`~livedrummer.midi.notemap.NoteMap.openness`) stops the hi-hat strokes strictly before
it: the top cymbal comes down on the ringing one, as the picture's does. Strictly, because a
module sends the pedal before the note, often in the same packet: a closed stroke or a pedal
"chick" stamped with the closing's own time is the closed hat's sound, not one it stops.

Both become one list of cut times per kit piece, the layout every renderer takes as
``chokes`` (:func:`~livedrummer.audio.mix.choke_cut_s` is the rule: a stroke stops at the
first cut at or after it). A closing at ``t`` is listed as the largest float below ``t``, so
that rule cuts exactly the strokes before ``t``. Offline: :func:`sound_chokes` over a whole
performance's controls. Online: :class:`CutReader` fed one control row at a time in time
order (the live sound, :mod:`services.display.live_sound`) gives the same cuts, one by one.

Limits: a release (aftertouch 0) does nothing (the sound does not come back); the pedal's
state before its first row is unknown, so the first row never closes it; a half-open pedal
does not damp (only the crossing to closed cuts).
"""

from __future__ import annotations

import math

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import NoteMap
from livedrummer.timeline.events import ControlKind

#: Openness (0 closed ... 1 open) at or below which the hi-hat counts as closed.
CLOSED_AT = 0.1


class CutReader:
    """Control rows in, cuts out: ``take(row)`` is ``(piece index in kit, cut time s)``,
    or None for a row that cuts nothing (see the module docstring)."""

    def __init__(self, note_map: NoteMap, kit: Kit) -> None:
        self.note_map = note_map
        self.kit = kit
        self._index = {p.name: k for k, p in enumerate(kit.pieces)}
        hat = kit.resolve("hihat")
        self.hat: int | None = None if hat is None else self._index[hat.name]
        self._open: dict[int, bool] = {}  # per MIDI channel: the pedal was open at its last row

    def reset(self) -> None:
        self._open.clear()

    def take(self, row: np.void | np.ndarray) -> tuple[int, float] | None:
        kind, t = int(row["kind"]), float(row["time_s"])
        if kind == ControlKind.CHOKE:
            if int(row["value"]) == 0:
                return None
            spec = self.note_map.lookup(int(row["number"]))
            piece = self.kit.resolve(spec.instrument) if spec is not None else None
            return None if piece is None else (self._index[piece.name], t)
        if kind != ControlKind.HIHAT_PEDAL:
            return None
        channel = int(row["channel"])
        was_open = self._open.get(channel)
        is_open = self.note_map.openness(int(row["value"])) > CLOSED_AT
        self._open[channel] = is_open
        if was_open and not is_open and self.hat is not None:
            return self.hat, math.nextafter(t, -math.inf)  # strictly after the strokes it cuts
        return None


def sound_chokes(controls: np.ndarray, note_map: NoteMap, kit: Kit) -> list[np.ndarray]:
    """Sorted cut times per piece of ``kit`` (the ``chokes`` layout) from ``controls``."""
    reader = CutReader(note_map, kit)
    out: list[list[float]] = [[] for _ in kit.pieces]
    for row in np.sort(controls, order="time_s", kind="stable") if controls.size else controls:
        cut = reader.take(row)
        if cut is not None:
            out[cut[0]].append(cut[1])
    return [np.sort(np.asarray(v, dtype=np.float64)) for v in out]
