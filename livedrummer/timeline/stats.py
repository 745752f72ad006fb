"""What a reader counted of its source: every note and message, kept or not.

Why here. The MIDI decoder (:mod:`livedrummer.midi.decode`) fills these counts as it reads,
and a :class:`~livedrummer.timeline.performance.Performance` carries them so that every
command can say what was skipped and why
(:meth:`~livedrummer.timeline.performance.Performance.report_lines`).
The record sits with the performance, below the readers that fill it, so the timeline package
needs nothing from ``midi``. Limits: the counters are MIDI's words (notes, channels, message
types); a reader of another format fills the ones that apply.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field


@dataclass
class DecodeStats:
    """Counts of everything the decoder saw, kept or not."""

    note_ons: Counter[int] = field(default_factory=Counter)  # velocity > 0, per note, raw
    unknown_notes: Counter[int] = field(default_factory=Counter)
    ignored_notes: Counter[int] = field(default_factory=Counter)  # the map's *ignored* class
    other_channel_notes: Counter[int] = field(default_factory=Counter)  # 0-based channel
    duplicates_removed: int = 0
    onsets: int = 0
    hihat_pedal: int = 0
    chokes: int = 0
    strike_positions: int = 0
    ignored: Counter[str] = field(default_factory=Counter)  # by message type
