"""A played take written as a Standard MIDI File on the reference's clock.

``practice --take out.mid`` writes what the player hit so that ``practice score REF.mid
out.mid`` judges it exactly as the live rig did: time zero is the reference's time zero (not
the first hit, as ``sessions export`` writes) plus a lead of :data:`LEAD_S`, at 120 bpm and
1920 ticks per beat (0.26 ms per tick), every onset a note-on with its own note number,
velocity and channel and a note-off 50 ms later (or just before the same note sounds again).

The lead is there because a player may hit the first note a little early, before the
reference's time zero, and a MIDI file has no time before its own zero. The file says how long
its lead is in a marker at tick 0 (``livedrummer take: reference starts at 1.000 s``), which
``practice score`` reads (:func:`read_lead_s`) and subtracts, so the take is judged on the
reference's clock; any other MIDI file has no such marker and no lead. Onsets earlier than the
lead (a hit during the count-in) are left out; the caller counts them.
"""

from __future__ import annotations

from pathlib import Path

import mido
import numpy as np

from livedrummer.errors import LivedrummerError

TAKE_BPM = 120.0
TAKE_TPB = 1920
NOTE_S = 0.05
LEAD_S = 1.0
_MARKER = "livedrummer take: reference starts at "


def on_take_grid(times_s: np.ndarray, lead_s: float = LEAD_S) -> np.ndarray:
    """``times_s`` (the reference's clock) as the take file holds them: on its tick grid.

    The live rig judges its hits on this grid (0.26 ms; far finer than any kit's timing), so
    ``practice score`` of the file, which can only see the ticks, grades each hit in the same
    window as the pass did, even one within a tick of a grade's edge."""
    ticks_per_s = TAKE_TPB * TAKE_BPM / 60.0
    out: np.ndarray = np.round((np.asarray(times_s, np.float64) + lead_s) * ticks_per_s)
    return out / ticks_per_s - lead_s


def take_to_midi(onsets: np.ndarray, lead_s: float = LEAD_S) -> mido.MidiFile:
    """``onsets`` (ONSET_DTYPE, times on the reference's clock) as a one-track SMF."""
    ticks_per_s = TAKE_TPB * TAKE_BPM / 60.0
    rows = onsets[onsets["time_s"] >= -lead_s].copy()
    rows["time_s"] += lead_s
    rows = rows[np.argsort(rows["time_s"], kind="stable")]
    events: list[tuple[int, int, int, mido.Message]] = []
    pending: dict[tuple[int, int], int] = {}
    for k, row in enumerate(rows.tolist()):
        t_s, note, velocity, channel = float(row[0]), int(row[1]), int(row[2]), int(row[3])
        tick = round(t_s * ticks_per_s)
        key = (channel, note)
        if key in pending:
            off = min(pending.pop(key), tick)
            events.append((off, 0, k, mido.Message("note_off", channel=channel, note=note)))
        msg = mido.Message("note_on", channel=channel, note=note, velocity=max(1, velocity))
        events.append((tick, 1, k, msg))
        pending[key] = tick + max(1, round(NOTE_S * ticks_per_s))
    for (channel, note), off in pending.items():
        events.append((off, 0, len(events), mido.Message("note_off", channel=channel, note=note)))
    events.sort(key=lambda e: e[:3])
    mid = mido.MidiFile(type=0, ticks_per_beat=TAKE_TPB)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=round(60_000_000 / TAKE_BPM), time=0))
    if lead_s:
        track.append(mido.MetaMessage("marker", text=f"{_MARKER}{lead_s:.6f} s", time=0))
    now = 0
    for tick, _, _, msg in events:
        track.append(msg.copy(time=tick - now))
        now = tick
    track.append(mido.MetaMessage("end_of_track", time=0))
    mid.tracks.append(track)
    return mid


def read_lead_s(midi: mido.MidiFile) -> float:
    """The lead a take file declares in its marker (0.0 for any other MIDI file)."""
    for track in midi.tracks:
        for msg in track:
            if msg.time:
                break
            if msg.type == "marker" and msg.text.startswith(_MARKER):
                try:
                    return float(msg.text[len(_MARKER) :].removesuffix(" s"))
                except ValueError:
                    return 0.0
    return 0.0


def write_take(path: Path, onsets: np.ndarray, lead_s: float = LEAD_S) -> None:
    """Write the take (see the module docstring); one line naming the file if it cannot."""
    try:
        take_to_midi(onsets, lead_s).save(path)
    except OSError as exc:
        raise LivedrummerError(f"{path}: cannot write the take: {exc.strerror or exc}") from None


def take_lead_s(path: Path) -> float:
    """:func:`read_lead_s` of the file at ``path`` (already read once by the caller: a file
    that cannot be parsed here has no lead)."""
    from livedrummer.midi.smf import parse_smf, unwrap_rmid

    try:
        data, where = unwrap_rmid(path.read_bytes(), str(path))
        return read_lead_s(parse_smf(data, where)[0])
    except (OSError, LivedrummerError):
        return 0.0
