"""The drum track from a General MIDI SoundFont (``--soundfont FILE.sf2``), through FluidSynth.

The built-in kit (:mod:`~livedrummer.audio.mix`) needs nothing; a user who owns a SoundFont can
have its drum kit instead. FluidSynth (``libfluidsynth3``, via the ``pyfluidsynth`` ctypes
binding, imported lazily so nothing else depends on it) renders offline: a synth with no audio
driver, the GM percussion kit (bank 128, preset 0) on channel 10, and for each onset the synth
is advanced to the onset's sample and sent a note-on; a note-off follows :data:`NOTE_HOLD_S`
later (or at the next stroke of the same note) since drums are one-shots and a SoundFont
shapes their decay with its release envelope. Hi-hat chokes are the SoundFont's own exclusive
classes. Output is float32 stereo, same length and placement as :func:`mix_onsets`, scaled
down as a whole only if it would clip.

Cymbal chokes (grabs per kit piece; :func:`~livedrummer.audio.mix.choke_cut_s` is the rule
the built-in kit applies too). A note-off at the grab would only start the SoundFont's own
release, which for a crash lasts seconds, so the strokes a grab stops are rendered apart: each
group of strokes ended by one grab goes through a second synth, from its first note-on to the
grab plus :data:`~livedrummer.audio.mix.GRAB_FADE_S`, fades out over those last 5 ms and is
added to the mix; all other strokes play through the main synth as before. FluidSynth mixes
linearly, so the sum is the unchoked render with the choked strokes stopped. Every group is
rendered in whole 64-sample blocks, so the second synth's blocks (where note-ons take effect)
stay on the track's grid, and through a scratch buffer of
:data:`~livedrummer.audio.mix.STEP` samples, so memory does not grow with a group's length.
Between two groups the second synth's voices are turned off and :data:`FLUSH_S` of silence is
rendered and dropped, so one group's reverb does not sound in the next (a system reset, in
FluidSynth 2.3, left the voices playing).

Limits of the choke render: a choked stroke shares no voice stealing or exclusive class with the
main synth's strokes; the reverb's and chorus's modulation runs on each synth's own clock, so a
choked stroke's wet sound is not the one it has in the main synth (TimGM6mb on a GMD groove:
the difference is 1 % of the track's RMS over the groove, 11 % in the 0.3 s before a grab of a
ringing crash; with reverb and chorus off the two renders agree to 6e-6 RMS); the first block
of a voice the second synth used before differs from a fresh voice's by a few per cent of the
stroke's peak. A group spans every stroke of its piece since the previous grab, so a choked
piece is rendered twice: a 165 s GMD groove with 8 grabs took 4.5-5.3 s instead of 2.7-3.6 s
(a busy two-core machine).

Which note sounds: :func:`~livedrummer.midi.gm.gm_notes`, the General MIDI note that
means the onset's instrument, zone and hi-hat articulation.

Timing limit: FluidSynth starts a voice at the start of its next 64-sample block, so a note-on
is sent at the block boundary nearest the onset: attacks land within 32 samples (0.67 ms at
48 kHz) of their onsets, either side. Errors (no FluidSynth library, a missing or unreadable
file, no drum kit in it) are :class:`SoundFontError` naming the file; FluidSynth's own log
messages, and what native code prints while loading, go to :mod:`logging` at DEBUG.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import logging
import math
from collections.abc import Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.audio.mix import GRAB_FADE_S, STEP, choke_cut_s, fit_headroom, track_buffer
from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.errors import LivedrummerError
from livedrummer.kit.model import Kit
from livedrummer.midi.gm import gm_notes
from livedrummer.native.stderr import native_stderr_to_log

log = logging.getLogger(__name__)

DRUM_CHANNEL = 9  # MIDI channel 10
DRUM_BANK, DRUM_PRESET = 128, 0
NOTE_HOLD_S = 0.1
BLOCK = 64  # FluidSynth's rendering block (FLUID_BUFSIZE)
FLUSH_S = 3.0  # silence rendered between choked groups: the default reverb falls 100 dB
GAIN = 0.6  # FluidSynth's default 0.2 leaves a drum track quiet; clipping is scaled away


class SoundFontError(LivedrummerError):
    """A SoundFont cannot be used: no FluidSynth, no such file, not an SF2, no drum kit."""


_errors: list[str] = []  # FluidSynth's error messages since the last load began
_held: list[list[str]] = []  # while loading: its messages, logged once fd 2 is back
_LOG_FUNC = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_char_p, ctypes.c_void_p)


def _on_log(level: int, message: bytes | None, _data: int | None) -> None:
    """FluidSynth's messages, at DEBUG: what matters reaches the user in the error itself."""
    text = f"fluidsynth (level {level}): " + (message or b"").decode(errors="replace").strip()
    if level <= 1:  # FLUID_PANIC, FLUID_ERR
        _errors.append(text.split(": ", 1)[1])
    if _held:
        _held[-1].append(text)
    else:
        log.debug("%s", text)


@contextlib.contextmanager
def _loading() -> Iterator[None]:
    """Collect FluidSynth's errors, and the native noise written straight to file descriptor 2
    (:func:`~livedrummer.native.stderr.native_stderr_to_log`), for the DEBUG log instead of the
    user's one-line error."""
    _errors.clear()
    _held.append([])
    try:
        with native_stderr_to_log(log, "stderr"):
            yield
    finally:
        for line in _held.pop():
            log.debug("%s", line)


_log_callback = _LOG_FUNC(_on_log)  # kept alive: FluidSynth holds the pointer


@cache
def _fluidsynth() -> tuple[Any, Any]:
    """The pyfluidsynth module and the library's ``fluid_synth_write_float``; logs routed."""
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # it prints where it found the library
            import fluidsynth
        lib = ctypes.CDLL(fluidsynth.lib)
    except (ImportError, OSError) as exc:
        raise SoundFontError(
            f"the FluidSynth library cannot be loaded ({exc}); "
            "Debian: apt-get install libfluidsynth3"
        ) from None
    for level in range(5):
        lib.fluid_set_log_function(level, _log_callback, None)
    write = lib.fluid_synth_write_float
    write.argtypes = [
        ctypes.c_void_p,
        ctypes.c_int,
        ctypes.c_void_p,
        ctypes.c_int,
        ctypes.c_int,
        ctypes.c_void_p,
        ctypes.c_int,
        ctypes.c_int,
    ]
    write.restype = ctypes.c_int
    return fluidsynth, write


def _open(path: Path, sr: int) -> tuple[Any, Any, int]:
    """A FluidSynth synth (no audio driver) with ``path``'s drum kit on channel 10, the
    library's write function and the SoundFont's id in the synth."""
    try:
        fluidsynth, write = _fluidsynth()
    except SoundFontError as exc:
        raise SoundFontError(f"soundfont {path}: {exc}") from None
    try:
        with path.open("rb") as f:
            head = f.read(12)
    except OSError as exc:
        raise SoundFontError(f"soundfont {path}: {exc.strerror or exc}") from None
    if head[:4] != b"RIFF" or head[8:12] != b"sfbk":
        raise SoundFontError(f"soundfont {path}: not a SoundFont 2 file (no RIFF sfbk header)")
    synth = fluidsynth.Synth(gain=GAIN, samplerate=sr, **{"synth.lock-memory": 0})
    try:
        with _loading():
            sfid = synth.sfload(str(path))
        if sfid < 0:
            why = _errors[0] if _errors else "FluidSynth cannot load it"
            raise SoundFontError(f"soundfont {path}: not a usable SoundFont 2 file ({why})")
        if synth.program_select(DRUM_CHANNEL, sfid, DRUM_BANK, DRUM_PRESET) < 0:
            raise SoundFontError(
                f"soundfont {path}: no General MIDI drum kit (bank {DRUM_BANK}, preset "
                f"{DRUM_PRESET})"
            )
    except BaseException:
        synth.delete()
        raise
    return synth, write, sfid


def check_soundfont(path: Path, sr: int = SAMPLE_RATE) -> None:
    """Raise :class:`SoundFontError` now if ``path`` would fail later (before a long show)."""
    synth, _write, _sfid = _open(path, sr)
    synth.delete()


def render_soundfont(
    onsets: np.ndarray,
    duration_s: float,
    path: Path,
    sr: int = SAMPLE_RATE,
    kit: Kit | None = None,
    chokes: Sequence[np.ndarray] | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Stereo float32 (N, 2), N = round(duration_s * sr): every onset played by ``path``; a
    grab in ``chokes`` (per piece of ``kit``) stops its piece's strokes (module docstring).
    ``out``: the zeroed buffer to render into and return, as for :func:`mix_onsets`."""
    n = round(duration_s * sr)
    out = track_buffer(n, out)
    notes = gm_notes(onsets)
    cuts = choke_cut_s(onsets, kit, chokes)
    free = ~np.isfinite(cuts)
    synth, write, _sfid = _open(path, sr)
    try:
        _play(synth, write, out, _events(onsets[free], notes[free], n, sr), 0)
    finally:
        synth.delete()
    if not free.all():
        _add_choked(out, onsets, notes, cuts, path, sr)
    fit_headroom(out)
    return out


def _play(
    synth: Any, write: Any, out: np.ndarray, events: list[tuple[int, int, int]], pos: int
) -> None:
    """Send ``events`` to ``synth``, rendering into ``out`` from sample ``pos`` to its end."""
    for at, velocity, note in events:
        if at > pos:
            _render(write, synth.synth, out, pos, at)
            pos = at
        if velocity:
            synth.noteon(DRUM_CHANNEL, note, velocity)
        else:
            synth.noteoff(DRUM_CHANNEL, note)
    if out.shape[0] > pos:
        _render(write, synth.synth, out, pos, out.shape[0])


def _add_choked(
    out: np.ndarray, onsets: np.ndarray, notes: np.ndarray, cuts: np.ndarray, path: Path, sr: int
) -> None:
    """Each group of strokes one grab stops, rendered alone to the grab and faded into ``out``
    (through a scratch buffer of at most :data:`~livedrummer.audio.mix.STEP` samples: a group
    may span the whole show)."""
    n = out.shape[0]
    fade = max(2, round(GRAB_FADE_S * sr))
    # whole 64-sample blocks rendered per group, so the synth's blocks stay on the track's grid
    # (a note-on takes effect at the synth's next block boundary)
    flush = BLOCK * math.ceil(FLUSH_S * sr / BLOCK)
    scratch = np.zeros((max(flush, STEP), 2), np.float32)
    synth, write, _sfid = _open(path, sr)
    try:
        for cut_s in np.unique(cuts[np.isfinite(cuts)]).tolist():
            group = cuts == cut_s
            events = _events(onsets[group], notes[group], n, sr)
            grab = round(cut_s * sr)
            stop = min(n, grab + fade)
            if not events or events[0][0] >= stop:
                continue
            synth.all_sounds_off(DRUM_CHANNEL)  # the last group's voices; then its reverb
            _render(write, synth.synth, scratch, 0, flush)  # and chorus die away
            pos, end = events[0][0], BLOCK * math.ceil(stop / BLOCK)
            for at, velocity, note in [*(e for e in events if e[0] < stop), (end, 0, -1)]:
                while pos < at:
                    k = min(STEP, at - pos)
                    _render(write, synth.synth, scratch, 0, k)
                    part, m = scratch[:k], max(0, min(k, stop - pos))
                    if pos + k > grab:  # from the grab on: 1 down to 0 over ``fade`` samples
                        gain = 1.0 - (np.arange(pos, pos + k) - grab) / (fade - 1)
                        part = part * np.clip(gain, 0.0, 1.0).astype(np.float32)[:, None]
                    out[pos : pos + m] += part[:m]
                    pos += k
                if note < 0:
                    break
                if velocity:
                    synth.noteon(DRUM_CHANNEL, note, velocity)
                else:
                    synth.noteoff(DRUM_CHANNEL, note)
    finally:
        synth.delete()


def _events(onsets: np.ndarray, notes: np.ndarray, n: int, sr: int) -> list[tuple[int, int, int]]:
    """(sample, velocity or 0 for note-off, note), in the order to send them."""
    hold = round(NOTE_HOLD_S * sr)
    starts = [BLOCK * round(float(t) * sr / BLOCK) for t in onsets["time_s"]]
    events: list[tuple[int, int, int]] = []
    next_same: dict[int, int] = {}
    for i in sorted(range(len(starts)), key=lambda k: starts[k], reverse=True):
        start, note = starts[i], int(notes[i])
        if not 0 <= start < n:
            continue
        off = min(start + hold, next_same.get(note, start + hold))
        next_same[note] = start
        events.append((start, max(1, int(onsets["velocity"][i])), note))
        if off < n:
            events.append((off, 0, note))
    events.sort(key=lambda e: (e[0], e[1] > 0))  # a note-off before a note-on at one sample
    return events


def _render(write: Any, synth: Any, out: np.ndarray, start: int, stop: int) -> None:
    base = out.ctypes.data
    if write(synth, stop - start, base, 2 * start, 2, base, 2 * start + 1, 2) != 0:
        raise SoundFontError("FluidSynth failed to render")
