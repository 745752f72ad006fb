"""Received pose samples kept by show time, and turned into renderer frames.

The display asks "what does the drummer look like at show time t?" for the time its next
frame will be seen. :class:`PoseTrack` keeps the last few seconds of samples (bounded) and
answers with the latest sample at or before ``t`` (poses are sampled at 240 Hz and every
contact is a sample of its own, so holding one is at most 4 ms off and never skips a
contact). When the stream stops, the last pose is held; when it resumes, newer samples win.
:func:`scene_frame` maps the body's pose record onto the renderer's rest skeleton (same
joints, other names) and the kit channels.

Limits: no interpolation between samples; samples older than ``keep_s`` behind the newest
are forgotten.
"""

from __future__ import annotations

import numpy as np

from livedrummer.body.skeleton import J
from livedrummer.scene import CH_HIGHLIGHT, CH_TRAVEL, CH_WOBBLE, N_CHANNELS, SceneFrame

#: Renderer (scene_rest) joint order, as body joints.
SCENE_JOINTS = (
    "pelvis", "lower_back", "chest", "neck", "head", "head_top",
    "r_shoulder", "r_elbow", "r_wrist", "r_stick",
    "l_shoulder", "l_elbow", "l_wrist", "l_stick",
    "r_hip", "r_knee", "r_ankle", "r_toe",
    "l_hip", "l_knee", "l_ankle", "l_toe",
)  # fmt: skip
_INDEX = np.array([J[n] for n in SCENE_JOINTS])
_STICKS = np.array([[J["r_stick"], J["r_tip"]], [J["l_stick"], J["l_tip"]]])


class PoseTrack:
    """See the module docstring."""

    def __init__(self, keep_s: float = 3.0) -> None:
        self.keep_s = keep_s
        self.reset()

    def reset(self) -> None:
        self._show = np.zeros(0)
        self._rows: np.ndarray | None = None
        self.received = 0

    def add(self, show_s: np.ndarray, rows: np.ndarray) -> None:
        """Samples with float64 show times (ascending)."""
        if show_s.size == 0:
            return
        self.received += show_s.size
        if self._rows is None or self._rows.dtype != rows.dtype:
            self._show, self._rows = show_s.copy(), rows.copy()
        else:
            keep = self._show < show_s[0]  # a resent range replaces what it covers
            self._show = np.concatenate([self._show[keep], show_s])
            self._rows = np.concatenate([self._rows[keep], rows])
        cut = np.searchsorted(self._show, self._show[-1] - self.keep_s)
        if cut > 0:
            self._show, self._rows = self._show[cut:], self._rows[cut:]

    @property
    def newest_s(self) -> float | None:
        return float(self._show[-1]) if self._show.size else None

    def at(self, show_s: float) -> tuple[float, np.ndarray] | None:
        """The latest sample at or before ``show_s`` (the earliest if all are later)."""
        if self._rows is None or self._show.size == 0:
            return None
        i = max(int(np.searchsorted(self._show, show_s, side="right")) - 1, 0)
        return float(self._show[i]), self._rows[i]


def scene_frame(row: np.ndarray, time_s: float, travel_is_swing: np.ndarray) -> SceneFrame:
    """A renderer frame from one pose record; ``travel_is_swing`` (P,) marks the pieces whose
    travel channel is the beater's swing (the kick) rather than the hi-hat's lift."""
    pos = np.asarray(row["position"], np.float32)
    channels = np.zeros((row["glow"].shape[0], N_CHANNELS), np.float32)
    channels[:, CH_HIGHLIGHT] = row["glow"]
    channels[:, CH_WOBBLE] = np.where(travel_is_swing, 0.0, row["swing"])
    channels[:, CH_TRAVEL] = np.where(travel_is_swing, row["swing"], row["lift"])
    return SceneFrame(pos[_INDEX].copy(), pos[_STICKS].copy(), channels, time_s)
