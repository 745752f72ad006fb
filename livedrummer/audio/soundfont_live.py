"""A General MIDI SoundFont played live: the online twin of
:func:`~livedrummer.audio.soundfont.render_soundfont`.

One FluidSynth synth with no audio driver (the same settings, drum kit and gain as the offline
render, opened by :func:`~livedrummer.audio.soundfont._open`). :meth:`SoundFontLiveMixer.add`
queues a stroke's note-on at its sample on the output stream, rounded to FluidSynth's
64-sample block grid as the offline render rounds it, and its note-off :data:`~livedrummer.
audio.soundfont.NOTE_HOLD_S` later or at the next stroke of the same note, whichever is first
(the offline rule; a later stroke that arrives first still cuts an earlier one's hold).
:meth:`SoundFontLiveMixer.render` renders each output block in pieces: up to the next queued
event's sample, the event, then on; so the synth's blocks stay on the stream's grid and every
note-on takes effect on the sample the offline render starts it on. FluidSynth's output does
not depend on how its blocks are grouped into calls, so, fed the same strokes, the live
stream is the offline track sample for sample wherever the offline one was not scaled for
headroom (the reverb and chorus run on the synth's own block count, the same in both).

Limits: those of :class:`~livedrummer.audio.live_mix.LiveMixer` (no cymbal grabs live: a grab
is not forwarded to displays; a sum over full scale is clipped at 1 and counted, not scaled).
A stroke that arrives after its sample was rendered starts at the next block FluidSynth
renders. Rendering runs in the caller's thread (the sound process's loop), costing one
``fluid_synth_write_float`` per event and block.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from livedrummer.audio.live_mix import LiveMixer
from livedrummer.audio.soundfont import (
    BLOCK,
    DRUM_CHANNEL,
    NOTE_HOLD_S,
    _gm_tables,
    _open,
    _render,
    gm_note,
)
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES


class SoundFontLiveMixer(LiveMixer):
    """See the module docstring; :meth:`close` frees the synth."""

    def __init__(self, path: Path, kit: Kit | None = None, sr: int = SAMPLE_RATE) -> None:
        super().__init__(kit, sr)
        self.path = path
        self._synth, self._write, _sfid = _open(path, sr)
        self._hold = round(NOTE_HOLD_S * sr)
        # queued events: [sample, velocity (0: note-off), note, the note-on's sample]
        self._events: list[list[int]] = []
        _gm_tables()  # read the note map now: on the first stroke it would make it late

    def add(self, onset: np.void | np.ndarray, start: int) -> None:
        note = gm_note(int(onset["note"]), INSTRUMENTS[int(onset["instrument"])],
                       ZONES[int(onset["zone"])], HIHATS[int(onset["hihat"])])  # fmt: skip
        at = max(self.rendered, BLOCK * round(start / BLOCK))
        off = at + self._hold
        for event in self._events:
            if event[2] != note:
                continue
            if event[1] and event[0] > at:  # a later stroke of this note, queued already
                off = min(off, event[0])
            elif not event[1] and event[3] < at < event[0]:  # an earlier one's hold: cut here
                event[0] = at
        self._events.append([at, max(1, int(onset["velocity"])), note, at])
        self._events.append([off, 0, note, at])

    def render(self, n: int) -> np.ndarray:
        lo, hi = self.rendered, self.rendered + n
        out = np.zeros((n, 2), np.float32)
        due = sorted((e for e in self._events if e[0] < hi), key=lambda e: (e[0], e[1] > 0))
        self._events = [e for e in self._events if e[0] >= hi]
        pos = 0
        for at, velocity, note, _on in due:
            k = max(0, at - lo)
            if k > pos:
                _render(self._write, self._synth.synth, out, pos, k)
                pos = k
            if velocity:
                self._synth.noteon(DRUM_CHANNEL, note, velocity)
            else:
                self._synth.noteoff(DRUM_CHANNEL, note)
        if n > pos:
            _render(self._write, self._synth.synth, out, pos, n)
        self.rendered = hi
        over = np.abs(out) > 1.0
        if over.any():
            self.clipped += int(over.sum())
            np.clip(out, -1.0, 1.0, out=out)
        return out

    def close(self) -> None:
        if self._synth is not None:
            self._synth.delete()
            self._synth = None
