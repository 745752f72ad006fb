"""Hits against a MIDI ground truth: onset F-measure per class and overall, counted one way.

How we count (the figures in docs/benchmarks/acoustic.md come from this function):

- A detected hit matches a true note of the **same class** within ``±tolerance_s`` (25 ms);
  matching is one-to-one, greedy in order of time distance (closest pairs first).
- **Merged:** true notes of one class closer than ``merge_s`` (30 ms) to the previous kept
  note of that class are one onset (a flam is heard as one hit).
- **Don't care:** true notes with no class (hi-hat pedal chicks, hand percussion) and *ghost
  notes*, whose level is ``ghost_db`` (30 dB) or more below the loudest note of their class in
  the file, with level ``40 log10(velocity)`` dB (a General MIDI synth's amplitude grows about
  as velocity squared). A detection matching a don't-care note (same class for ghosts, any
  class for unclassed notes) is neither a hit nor a false alarm; an unmatched one is not a
  miss.
- ``groups`` fold classes together before matching (e.g. closed and open hi-hat as one
  "hihat": an open hi-hat heard as closed counts as found in that row).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from livedrummer.acoustic.pieces import CLASSES


@dataclass(frozen=True)
class Counts:
    tp: int
    fp: int
    fn: int

    @property
    def precision(self) -> float:
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else 1.0

    @property
    def recall(self) -> float:
        return self.tp / (self.tp + self.fn) if self.tp + self.fn else 1.0

    @property
    def f(self) -> float:
        d = 2 * self.tp + self.fp + self.fn
        return 2 * self.tp / d if d else 1.0

    def __add__(self, other: Counts) -> Counts:
        return Counts(self.tp + other.tp, self.fp + other.fp, self.fn + other.fn)


def _match(det: np.ndarray, ref: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Boolean masks of matched detections and references (one-to-one, closest first)."""
    used_d = np.zeros(len(det), bool)
    used_r = np.zeros(len(ref), bool)
    if len(det) and len(ref):
        dist = np.abs(det[:, None] - ref[None, :])
        pairs = np.argwhere(dist <= tol)
        for i, j in sorted(pairs.tolist(), key=lambda ij: dist[ij[0], ij[1]]):
            if not used_d[i] and not used_r[j]:
                used_d[i] = used_r[j] = True
    return used_d, used_r


def _merge(times: np.ndarray, merge_s: float) -> np.ndarray:
    keep: list[float] = []
    for t in np.sort(times).tolist():
        if not keep or t - keep[-1] >= merge_s:
            keep.append(t)
    return np.array(keep)


def score(
    det_times: np.ndarray,
    det_classes: np.ndarray,
    ref_times: np.ndarray,
    ref_classes: np.ndarray,
    ref_velocities: np.ndarray,
    groups: Mapping[str, Sequence[str]] | None = None,
    tolerance_s: float = 0.025,
    merge_s: float = 0.030,
    ghost_db: float = 30.0,
) -> dict[str, Counts]:
    """Counts per class (or group) and ``"all"`` (see the module docstring)."""
    groups = groups or {c: (c,) for c in CLASSES}
    unclassed = ref_times[ref_classes < 0]
    out: dict[str, Counts] = {}
    total = Counts(0, 0, 0)
    for name, members in groups.items():
        codes = [CLASSES.index(c) for c in members]
        ref_in = np.isin(ref_classes, codes)
        det = np.sort(det_times[np.isin(det_classes, codes)])
        level = 40.0 * np.log10(np.maximum(ref_velocities[ref_in], 1).astype(float))
        loud = level > (level.max() - ghost_db if len(level) else 0.0)
        ref = _merge(ref_times[ref_in][loud], merge_s)
        ghosts = ref_times[ref_in][~loud]
        matched_d, matched_r = _match(det, ref, tolerance_s)
        spare = det[~matched_d]
        care_d, _ = _match(spare, np.concatenate([ghosts, unclassed]), tolerance_s)
        counts = Counts(int(matched_r.sum()), int((~care_d).sum()), int((~matched_r).sum()))
        out[name] = counts
        total = total + counts
    out["all"] = total
    return out
