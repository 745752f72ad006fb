"""Hits as onsets and as a General MIDI drum file (what ``livedrummer transcribe`` writes).

A hit becomes one note-on on channel 10 with its class's General MIDI note
(:data:`~.pieces.GM_NOTES`) and velocity, and a note-off 50 ms later (or at the next stroke of
the same note); the file is type 0 at 120 bpm, 480 ticks per beat (1.04 ms a tick), so a hit's
time is kept to half a tick. Every command that reads MIDI files reads it with the
``general-midi`` map (``--map auto`` picks it). As onsets on the bus a hit carries the same
note, its class's kit instrument and, for the hi-hat, the closed or open articulation.
"""

from __future__ import annotations

import mido
import numpy as np

from livedrummer.acoustic.pieces import CLASS_INSTRUMENT, CLASSES, GM_NOTES
from livedrummer.kit.vocabulary import INSTRUMENT_CODE, HiHat, Zone
from livedrummer.timeline.events import ONSET_DTYPE

DRUM_CHANNEL = 9
TICKS_PER_BEAT = 480
BPM = 120.0
NOTE_S = 0.05


def hits_to_onsets(hits: np.ndarray, source: int = 0) -> np.ndarray:
    """ONSET_DTYPE rows of hits (sorted by time)."""
    hits = np.sort(hits, order="time_s")
    out = np.zeros(len(hits), ONSET_DTYPE)
    cls = hits["cls"].astype(np.int64)
    out["time_s"] = hits["time_s"]
    out["note"] = np.array(GM_NOTES, np.uint8)[cls]
    out["velocity"] = hits["velocity"]
    out["channel"] = DRUM_CHANNEL
    out["instrument"] = [INSTRUMENT_CODE[CLASS_INSTRUMENT[c]] for c in cls.tolist()]
    hihat = np.full(len(hits), HiHat.NONE.code)
    hihat[cls == CLASSES.index("hihat_closed")] = HiHat.CLOSED.code
    hihat[cls == CLASSES.index("hihat_open")] = HiHat.OPEN.code
    out["hihat"] = hihat
    zone = np.full(len(hits), Zone.HEAD.code)
    cymbal = np.isin(
        cls, [CLASSES.index(c) for c in ("hihat_closed", "hihat_open", "crash", "ride")]
    )
    zone[cymbal] = Zone.BOW.code
    out["zone"] = zone
    openness = np.full(len(hits), np.nan)
    openness[cls == CLASSES.index("hihat_closed")] = 0.0
    openness[cls == CLASSES.index("hihat_open")] = 1.0
    out["openness"] = openness
    out["source"] = source
    return out


def hits_to_midi(hits: np.ndarray) -> mido.MidiFile:
    """A type-0 General MIDI drum file of the hits (see the module docstring)."""
    ticks_per_s = TICKS_PER_BEAT * BPM / 60.0
    events: list[tuple[int, int, mido.Message]] = []
    last_on: dict[int, int] = {}
    order = np.argsort(hits["time_s"], kind="stable")
    rows = [
        (
            max(0, round(float(hits["time_s"][i]) * ticks_per_s)),
            GM_NOTES[int(hits["cls"][i])],
            int(hits["velocity"][i]),
        )
        for i in order
    ]
    hold = max(1, round(NOTE_S * ticks_per_s))
    next_same: dict[int, int] = {}
    offs = [0] * len(rows)
    for k in range(len(rows) - 1, -1, -1):  # each note's next stroke ends it
        tick, note, _v = rows[k]
        offs[k] = min(tick + hold, next_same.get(note, tick + hold))
        next_same[note] = tick
    for k, (tick, note, velocity) in enumerate(rows):
        if last_on.get(note) == tick:
            continue  # one note once per tick
        last_on[note] = tick
        on = mido.Message(
            "note_on", channel=DRUM_CHANNEL, note=note, velocity=max(1, min(127, velocity))
        )
        events.append((tick, 1, on))
        off = mido.Message("note_off", channel=DRUM_CHANNEL, note=note)
        events.append((max(offs[k], tick + 1), 0, off))
    events.sort(key=lambda e: (e[0], e[1]))
    mid = mido.MidiFile(type=0, ticks_per_beat=TICKS_PER_BEAT)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=round(60_000_000 / BPM), time=0))
    now = 0
    for tick, _order, msg in events:
        track.append(msg.copy(time=tick - now))
        now = tick
    track.append(mido.MetaMessage("end_of_track", time=0))
    mid.tracks.append(track)
    return mid
