"""A performance: everything one MIDI file (or one recorded session) says, on one timeline.

Produced by :mod:`livedrummer.midi.smf` (or by a journal replay), consumed by limb assignment,
stroke synthesis and rendering. Onsets and controls are record arrays sorted by time (see
:mod:`livedrummer.timeline.events`); the grid and tempo map give the musical structure; ``stats``
keeps the count of everything that was not turned into an event, so reports can say what was
skipped and why; ``warnings`` are what the reader read past in a damaged file, ``notices`` the
reader's choices a person should know of (channels left out, the map ``auto`` chose).
:meth:`Performance.report_lines` is the one text every command prints about a file it reads.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat
from livedrummer.timeline.events import ControlKind
from livedrummer.timeline.stats import DecodeStats
from livedrummer.timeline.tempo import Grid, TempoMap


@dataclass(frozen=True)
class Performance:
    """Onsets and controls of one piece, with its tempo map, grid and decode statistics."""

    source: str
    map_name: str
    onsets: np.ndarray  # ONSET_DTYPE, sorted by time_s
    controls: np.ndarray  # CONTROL_DTYPE, sorted by time_s
    tempo: TempoMap
    grid: Grid
    duration_s: float
    stats: DecodeStats
    warnings: tuple[str, ...] = ()
    notices: tuple[str, ...] = ()
    channels: tuple[int, ...] | None = None  # 0-based channels read as drums; None: all

    def report_lines(self, note_labels: Mapping[int, str] | None = None) -> list[str]:
        """What a person must hear of this file: warnings, notices, notes left out, and that it
        has no drum notes if so (one line each; empty for a clean drum file).

        ``note_labels``: names of the map's ignored notes, for the ignored-notes line.
        """
        lines = [f"warning: {w}" for w in self.warnings]
        lines += self.notices
        unknown = self.stats.unknown_notes
        if unknown:
            listed = ", ".join(f"note {k} x{v}" for k, v in sorted(unknown.items()))
            lines.append(f"unknown notes: {listed} (not in map {self.map_name}; not played)")
        ignored = self.stats.ignored_notes
        if ignored:
            labels = note_labels or {}
            listed = ", ".join(
                f"note {k}{' ' + labels[k] if k in labels else ''} x{v}"
                for k, v in sorted(ignored.items())
            )
            lines.append(f"ignored notes: {listed} (no place on a drum kit; not played)")
        if not self.onsets.size:
            lines.append("no drum notes: nothing for the drummer to play")
        return lines

    def counts_by_piece_zone(self) -> dict[str, dict[str, int]]:
        """Onset counts per instrument, then per zone (hi-hat zones carry the articulation)."""
        out: dict[str, Counter[str]] = {}
        on = self.onsets
        keys = zip(
            on["instrument"].tolist(), on["zone"].tolist(), on["hihat"].tolist(), strict=True
        )
        for (inst, zone, hihat), n in Counter(keys).items():
            label = ZONES[zone].value
            if HIHATS[hihat] not in (HiHat.NONE, HiHat.PEDAL):
                label = f"{HIHATS[hihat].value}-{label}"
            out.setdefault(INSTRUMENTS[inst], Counter())[label] += n
        return {k: dict(sorted(v.items())) for k, v in sorted(out.items())}

    def summary(self) -> dict[str, Any]:
        """The facts ``livedrummer inspect`` reports, as plain JSON-ready data."""
        ctl = self.controls["kind"]
        hihat_mask = self.onsets["hihat"] != HIHATS.index(HiHat.NONE)
        openness = self.onsets["openness"][hihat_mask]
        return {
            "file": self.source,
            "map": self.map_name,
            "duration_s": round(self.duration_s, 6),
            "tempos_bpm": [[round(t, 6), round(b, 3)] for t, b in self.tempo.bpm_changes()],
            "meters": [[round(t, 6), n, d] for t, n, d in self.grid.meters],
            "beats": int(self.grid.beat_s.size),
            "bars": self.grid.bars,
            "onsets": int(self.onsets.size),
            "by_piece": self.counts_by_piece_zone(),
            "by_note": {str(k): v for k, v in sorted(self.stats.note_ons.items())},
            "unknown_notes": {str(k): v for k, v in sorted(self.stats.unknown_notes.items())},
            "ignored_notes": {str(k): v for k, v in sorted(self.stats.ignored_notes.items())},
            "channels": None if self.channels is None else [c + 1 for c in self.channels],
            "other_channel_notes": {
                str(c + 1): n for c, n in sorted(self.stats.other_channel_notes.items())
            },
            "warnings": list(self.warnings),
            "notices": list(self.notices),
            "duplicates_removed": self.stats.duplicates_removed,
            "hihat_pedal_events": int(np.count_nonzero(ctl == ControlKind.HIHAT_PEDAL)),
            "choke_events": int(np.count_nonzero(ctl == ControlKind.CHOKE)),
            "strike_position_events": int(np.count_nonzero(ctl == ControlKind.STRIKE_POSITION)),
            "hihat_openness_mean": round(float(openness.mean()), 4) if openness.size else None,
            "ignored_messages": dict(sorted(self.stats.ignored.items())),
        }
