"""Rhythm-game drum charts (Rock Band, Clone Hero, YARG MIDI charts): the drums of ``PART DRUMS``.

A chart is a MIDI file whose tracks are the game's instruments (``PART GUITAR``, ``PART BASS``,
``PART DRUMS``, ``EVENTS``...), all on channel 1, so the drum channel cannot tell them apart: the
drum track is found by its name (:func:`drum_track`). Its notes are gems in four difficulties,
markers and animation notes (see ``kits/maps/rock-band-chart.toml``, which cites the format's
documentation); the Expert gems are played.

Pro drums say whether a yellow, blue or green gem is a cymbal or a tom with *tom markers*: a
note 110, 111 or 112 held over the gem makes it a tom. :func:`apply_tom_markers` rewrites each
covered gem to the marker's note number (the map's tom entries) and takes the markers out of the
stream, counting them. At one tick a marker's end is applied before a gem and its start before a
gem, so a marker covers the gems from its first tick up to, not including, its last.

Limits: only the first drum track is read (``PART DRUMS`` before the ``_2X`` and Phase Shift
variants); disco flips, drum fills, the ``[ENABLE_CHART_DYNAMICS]`` event (velocities are
played as written) and the ``.chart`` text format are not read.
"""

from __future__ import annotations

from collections.abc import Sequence

import mido
import numpy as np

#: Names of drum tracks, in order of preference.
DRUM_TRACK_NAMES = ("PART DRUMS", "PART DRUMS_2X", "PART REAL_DRUMS_PS")
#: Tom marker note -> the gem it turns into a tom.
TOM_MARKERS = {110: 98, 111: 99, 112: 100}


def drum_track(tracks: Sequence[mido.MidiTrack]) -> int | None:
    """Index of the chart's drum track, or None if the file has none."""
    names = [t.name.strip().upper() for t in tracks]
    for wanted in DRUM_TRACK_NAMES:
        if wanted in names:
            return names.index(wanted)
    return None


def apply_tom_markers(
    messages: list[mido.Message], ticks: np.ndarray
) -> tuple[list[mido.Message], np.ndarray, int]:
    """The drum track's messages with covered gems rewritten as toms and the markers taken
    out (sorted by tick), and the number of marker notes taken out."""
    if not messages:
        return messages, ticks, 0
    priority: list[int] = []  # 0: a marker ends, 1: a marker starts, 2: anything else
    for msg in messages:
        if msg.type in ("note_on", "note_off") and msg.note in TOM_MARKERS:
            priority.append(1 if msg.type == "note_on" and msg.velocity > 0 else 0)
        else:
            priority.append(2)
    order = np.lexsort((np.array(priority), ticks))
    held = dict.fromkeys(TOM_MARKERS, 0)
    out: list[mido.Message] = []
    out_ticks: list[int] = []
    markers = 0
    for i in order.tolist():
        msg = messages[i]
        if priority[i] < 2:
            if priority[i] == 1:
                held[msg.note] += 1
                markers += 1
            else:
                held[msg.note] = max(0, held[msg.note] - 1)
            continue
        if msg.type == "note_on" and msg.velocity > 0:
            for marker, gem in TOM_MARKERS.items():
                if msg.note == gem and held[marker]:
                    msg = msg.copy(note=marker)
                    break
        out.append(msg)
        out_ticks.append(int(ticks[i]))
    return out, np.array(out_ticks, np.int64), markers
