"""MIDI thru re-mapping: a kit's raw messages rewritten for a General MIDI sampler.

``input --thru PORT --thru-map general-midi`` forwards what the kit sends with each note
renamed to the General MIDI percussion note that sounds the same stroke
(:func:`~livedrummer.midi.gm.gm_note`, the rule the SoundFont renderer uses: a
Roland TD's 22, a closed hi-hat edge, becomes 42) and put on channel 10, where GM samplers
play drums. Note-on, note-off and polyphonic aftertouch (the cymbal grab) are rewritten; a
note the kit's map does not know, and every other message (the hi-hat pedal's controller, the
clock), passes unchanged. Pure: bytes in, bytes out.
"""

from __future__ import annotations

from collections.abc import Callable

from livedrummer.midi.gm import gm_note
from livedrummer.midi.notemap import NoteMap

GM_CHANNEL = 9
NOTE_KINDS = (0x80, 0x90, 0xA0)  # note off, note on, polyphonic aftertouch
THRU_MAPS = ("general-midi",)

Remap = Callable[[list[int]], list[int]]


def gm_remap(note_map: NoteMap) -> Remap:
    """A function rewriting one raw MIDI message (a list of bytes) for a GM sampler."""
    table: dict[int, int] = {}
    for note in range(128):
        spec = note_map.lookup(note)
        if spec is not None:
            table[note] = gm_note(note, spec.instrument, spec.zone, spec.hihat)

    def remap(msg: list[int]) -> list[int]:
        if len(msg) == 3 and msg[0] & 0xF0 in NOTE_KINDS and msg[1] in table:
            return [(msg[0] & 0xF0) | GM_CHANNEL, table[msg[1]], msg[2]]
        return msg

    return remap
