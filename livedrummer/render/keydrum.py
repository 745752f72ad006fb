"""Keys played over a file: the sound of each key's piece and a glow and wobble on that piece.

In the file window (``livedrummer display FILE``) a key of the layout
(:mod:`livedrummer.midi.keypads`) sounds its piece through the window's player and lights and
shakes that piece on the kit, so a drummer can play along with the file. The file's drummer
does not change: the key is not a stroke of the performance (no arm moves, the score and the
file's track are untouched); only the piece answers. :class:`KeyDrum` turns a key press into
a one-shot sound (the same mixer as the file's track, :func:`~livedrummer.audio.mix.mix_onsets`,
so a key sounds like the file's own notes at that velocity) and keeps, per kit piece, the time
and loudness of its last key, which :meth:`KeyDrum.light` adds to a scene frame's channels as
a decaying glow (:data:`GLOW_S`) and wobble.

Limits: the note map that reads the key's General MIDI note is the window's (a file read with
a chart map may not know the notes, then the key is ignored, with one log line); one-shots
are rendered on the first press of each key and velocity and kept (a few hundred ms of audio).
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from livedrummer.audio.mix import mix_onsets
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HiHat
from livedrummer.midi.notemap import NoteMap
from livedrummer.render.scene import CH_HIGHLIGHT, CH_WOBBLE, SceneFrame
from livedrummer.timeline.events import ONSET_DTYPE, Onset

log = logging.getLogger(__name__)

GLOW_S = 0.25  #: time constant of a key's glow and wobble (e-folding, seconds)
SHOT_S = 1.5  #: length of a key's one-shot sound


class KeyDrum:
    """Key presses on a kit (see the module docstring)."""

    def __init__(self, kit: Kit, note_map: NoteMap, sr: int = SAMPLE_RATE) -> None:
        self.kit = kit
        self.note_map = note_map
        self.sr = sr
        self._index = {p.name: i for i, p in enumerate(kit.pieces)}
        self._last = np.full(len(kit.pieces), -np.inf)  # time of each piece's last key
        self._level = np.zeros(len(kit.pieces))  # its velocity / 127
        self._shots: dict[tuple[int, int], np.ndarray] = {}
        self.played = 0

    def onset(self, note: int, velocity: int, now_s: float) -> Onset | None:
        """The onset the key's note is under the note map, or None if the map does not know
        it."""
        spec = self.note_map.lookup(note)
        if spec is None:
            return None
        openness = float("nan")
        if spec.hihat is HiHat.PEDAL:
            openness = 0.0
        elif spec.hihat is not HiHat.NONE:
            openness = spec.hihat.nominal_openness
        return Onset(now_s, note, velocity, 9, spec.instrument, spec.zone, spec.hihat, openness)

    def piece_of(self, onset: Onset) -> int | None:
        piece = self.kit.resolve(onset.instrument)
        return None if piece is None else self._index[piece.name]

    def hit(self, note: int, velocity: int, now_s: float) -> np.ndarray | None:
        """Play ``note`` at ``now_s`` (the window's clock): light its piece and return its
        one-shot sound (stereo float32 (N, 2)), or None if the map or the kit lacks it."""
        onset = self.onset(note, velocity, now_s)
        piece = None if onset is None else self.piece_of(onset)
        if onset is None or piece is None:
            log.info("keys: note %d is not on this kit under map %r", note, self.note_map.name)
            return None
        self._last[piece] = now_s
        self._level[piece] = velocity / 127.0
        self.played += 1
        key = (note, velocity)
        if key not in self._shots:
            row = np.array([replace(onset, time_s=0.0).to_record()], ONSET_DTYPE)
            self._shots[key] = mix_onsets(row, SHOT_S, self.kit, self.sr)
        return self._shots[key]

    def glow(self, now_s: float) -> np.ndarray:
        """Per piece, the key glow at ``now_s`` (0..1)."""
        age = now_s - self._last
        out: np.ndarray = np.where(
            age >= 0.0, self._level * np.exp(-np.maximum(age, 0) / GLOW_S), 0.0
        )
        return out

    def light(self, frame: SceneFrame, now_s: float) -> SceneFrame:
        """``frame`` with each keyed piece's glow and wobble raised to the key's."""
        glow = self.glow(now_s).astype(np.float32)
        if not glow.any():
            return frame
        channels = frame.channels.copy()
        channels[:, CH_HIGHLIGHT] = np.maximum(channels[:, CH_HIGHLIGHT], glow)
        channels[:, CH_WOBBLE] = np.maximum(channels[:, CH_WOBBLE], glow)
        return replace(frame, channels=channels)
