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

Cuts (a grab, the closing hi-hat: :meth:`~livedrummer.audio.live_mix.LiveMixer.cut`). The
offline render plays the strokes a grab stops in a second synth, which a live mixer cannot
do: a stroke is sounding long before its grab is known. Live, each kit piece plays on a MIDI
channel of its own (the GM drum kit selected on each; the sound is the same as on channel 10,
sample for sample: with no cut the live stream is still the offline track), and a cut of the
piece turns that channel's volume (CC7) down to nothing in four 64-sample blocks from the
block nearest the cut (gains 3/4, 1/2, 1/4, 0: :data:`~livedrummer.audio.mix.GRAB_FADE_S`,
to the block), then sounds off and the volume back. So the dry sound stops at the cut as the
offline one does; what differs from the offline track is the reverb: the cut piece's reverb
tail rings on, as a room's would (TimGM6mb, a ringing crash: 22 dB below the crash at the cut),
where the offline render fades it too, and its reverb is shared with the other strokes.

Limits: those of :class:`~livedrummer.audio.live_mix.LiveMixer` (a sum over full scale is
clipped at 1 and counted, not scaled). A stroke that arrives after its sample was rendered
starts at the next block FluidSynth renders. A kit of more than 15 pieces plays the rest on
channel 10, where cuts do not reach; a stroke of a piece struck within the 5 ms of its cut's
fade is faded with it; a stroke that arrives after a cut it was struck before rings on.
Rendering runs in the caller's thread (the sound process's loop), costing one
``fluid_synth_write_float`` per event and block.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from livedrummer.audio.live_mix import LiveMixer
from livedrummer.audio.soundfont import (
    BLOCK,
    DRUM_BANK,
    DRUM_CHANNEL,
    DRUM_PRESET,
    NOTE_HOLD_S,
    _open,
    _render,
)
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES
from livedrummer.midi.gm import gm_note, warm_note_tables

VOLUME, SOUNDS_OFF = -1, -2  # the kinds of queued event that are not notes
DEFAULT_CC7 = 100  # General MIDI's channel volume at reset
# a cut's fade: CC7 for gains 3/4, 1/2, 1/4, 0 of the default (FluidSynth's volume curve takes
# the square of CC7 / 127 as the amplitude), one value a block
FADE_CC7 = tuple(round(DEFAULT_CC7 * g**0.5) for g in (0.75, 0.5, 0.25, 0.0))


class SoundFontLiveMixer(LiveMixer):
    """See the module docstring; :meth:`close` frees the synth."""

    def __init__(self, path: Path, kit: Kit | None = None, sr: int = SAMPLE_RATE) -> None:
        super().__init__(kit, sr)
        self.path = path
        self._synth, self._write, sfid = _open(path, sr)
        self._hold = round(NOTE_HOLD_S * sr)
        # queued events: [sample, velocity (0: note-off; VOLUME: CC7 = the note field; SOUNDS_OFF:
        # sounds off, CC7 back), note, the note-on's sample, channel]
        self._events: list[list[int]] = []
        self._channels = [c for c in range(16) if c != DRUM_CHANNEL]  # one per kit piece
        n_pieces = len(kit.pieces) if kit is not None else 0
        for channel in self._channels[:n_pieces]:
            self._synth.program_select(channel, sfid, DRUM_BANK, DRUM_PRESET)
        warm_note_tables()  # now: on the first stroke it would make it late

    def _channel(self, piece: int) -> int:
        return self._channels[piece] if 0 <= piece < len(self._channels) else DRUM_CHANNEL

    def add(self, onset: np.void | np.ndarray, start: int) -> None:
        instrument = INSTRUMENTS[int(onset["instrument"])]
        note = gm_note(
            int(onset["note"]), instrument, ZONES[int(onset["zone"])], HIHATS[int(onset["hihat"])]
        )
        channel = self._channel(self.piece_of(instrument))
        at = max(self.rendered, BLOCK * round(start / BLOCK))
        off = at + self._hold
        for event in self._events:
            if event[2] != note or event[1] < 0:
                continue
            if event[1] and event[0] > at:  # a later stroke of this note, queued already
                off = min(off, event[0])
            elif not event[1] and event[3] < at < event[0]:  # an earlier one's hold: cut here
                event[0] = at
        self._events.append([at, max(1, int(onset["velocity"])), note, at, channel])
        self._events.append([off, 0, note, at, channel])

    def cut(self, piece: int, time_s: float, at: int) -> None:
        """Fade the piece's channel out from the block nearest ``at`` (module docstring)."""
        channel = self._channel(piece)
        if channel == DRUM_CHANNEL:
            return
        at = max(self.rendered, BLOCK * round(at / BLOCK))
        for k, value in enumerate(FADE_CC7):
            self._events.append([at + k * BLOCK, VOLUME, value, at, channel])
        self._events.append([at + len(FADE_CC7) * BLOCK, SOUNDS_OFF, 0, at, channel])

    def render(self, n: int) -> np.ndarray:
        lo, hi = self.rendered, self.rendered + n
        out = np.zeros((n, 2), np.float32)
        due = sorted((e for e in self._events if e[0] < hi), key=lambda e: (e[0], e[1] > 0))
        self._events = [e for e in self._events if e[0] >= hi]
        pos = 0
        for at, velocity, note, _on, channel in due:
            k = max(0, at - lo)
            if k > pos:
                _render(self._write, self._synth.synth, out, pos, k)
                pos = k
            if velocity > 0:
                self._synth.noteon(channel, note, velocity)
            elif velocity == 0:
                self._synth.noteoff(channel, note)
            elif velocity == VOLUME:
                self._synth.cc(channel, 7, note)
            else:
                self._synth.all_sounds_off(channel)
                self._synth.cc(channel, 7, DEFAULT_CC7)
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
