"""The practice recording's drum track: the player's hits and the click, on the show's time.

``practice --headless --video FILE.mp4`` records the drummers as ``up --video`` does: the live
display places each frame on show time (:class:`~services.display.record.LiveRecorder`) and
writes the video's timing beside it; the drum track is muxed in when the session is over
(:func:`~services.display.record.mux_audio`). ``up`` reads its hits back from the session
journal; the practice rig does not need one: every hit the input daemon published reached the
rig's own subscription (:mod:`.bus`) with the driver's stamp the synth got too, and the rig
planned every click. So the track is :func:`~services.display.record.recording_track` of those
hits (the kit's sounds at hit + D, D the synth's delay, which the rig sets: the moment the
player's drummer strikes in the picture) plus each click (:func:`.click.click_wave`, the sound
and level of ``--click-sound``/``--click-level``) at click + D, so the click keeps its place
against the hits as the player heard it. The click is in the track even with ``--no-sound``,
which only silences the speaker; ``--click-level 0`` leaves it out.

Limits: the hi-hat pedal and cymbal chokes do not reach the rig (its subscription yields the
onsets), so a grabbed cymbal rings on in the track; the built-in kit only (no SoundFont: the
practice rig has no ``--soundfont``); a hit the display did not live to draw (after the
recording's last frame) is not in the track, as in ``up``'s.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import NoteMap
from livedrummer.timeline.events import CONTROL_DTYPE

from ..display.record import Timing, recording_track
from .click import RATE, click_wave


def practice_track(
    hits: np.ndarray,
    clicks_s: np.ndarray,
    accents: np.ndarray,
    timing: Timing,
    *,
    delay_s: float,
    kit: Kit,
    note_map: NoteMap,
    click_sound: str,
    click_level: float,
) -> np.ndarray:
    """The recording's track, (frames / fps * RATE, 2) float32: ``hits`` (ONSET_DTYPE on the
    shared clock) in ``kit``'s sounds and the clicks at ``clicks_s`` (shared clock; ``accents``
    the bars' first beats), each at its time + ``delay_s`` on the video's time."""
    controls = np.zeros(0, CONTROL_DTYPE)
    track = recording_track(
        hits, controls, timing, delay_s=delay_s, kit=kit, note_map=note_map, sample_rate=RATE
    )
    if click_level <= 0.0:
        return track
    waves = [click_wave(click_sound, accent, click_level) for accent in (False, True)]
    n = track.shape[0]
    for c, accent in zip(
        np.asarray(clicks_s, np.float64).tolist(), np.asarray(accents, bool).tolist(), strict=True
    ):
        wave = waves[int(accent)]
        first = round((c + delay_s - timing.show0_s) * RATE)
        a, b = max(0, first), min(n, first + wave.size)
        if b > a:
            track[a:b] += wave[a - first : b - first, None]
    return track
