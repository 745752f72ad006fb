"""Received pose samples kept by show time, and turned into renderer frames.

The display asks "what does the drummer look like at show time t?" for the time its next
frame will be seen. :class:`PoseTrack` keeps the last few seconds of samples (bounded) and
answers with the latest sample at or before ``t`` (poses are sampled at 240 Hz and every
contact is a sample of its own, so holding one is at most 4 ms off and never skips a
contact). When the stream stops, the last pose is held; when it resumes, newer samples win.
A batch that covers show times already held replaces exactly that range (the synth re-sends
what a late decision changed; a quick contact sent ahead of it is kept).
Records become renderer frames through :func:`livedrummer.render.body_scene.frame_from_pose`,
the same mapping the file renderer uses.

Limits: no interpolation between samples; samples older than ``keep_s`` behind the newest
are forgotten.
"""

from __future__ import annotations

import numpy as np


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
            # a batch replaces the range it covers, and only that range: samples sent after
            # it (a quick contact further on) stay
            lo = int(np.searchsorted(self._show, show_s[0], side="left"))
            hi = int(np.searchsorted(self._show, show_s[-1], side="right"))
            self._show = np.concatenate([self._show[:lo], show_s, self._show[hi:]])
            self._rows = np.concatenate([self._rows[:lo], rows, self._rows[hi:]])
        cut = np.searchsorted(self._show, self._show[-1] - self.keep_s)
        if cut > 0:
            self._show, self._rows = self._show[cut:], self._rows[cut:]

    @property
    def show_s(self) -> np.ndarray:
        """The kept samples' show times (ascending, read-only view)."""
        out = self._show.view()
        out.flags.writeable = False
        return out

    @property
    def rows(self) -> np.ndarray:
        """The kept pose records, matching :attr:`show_s`."""
        return self._rows if self._rows is not None else np.zeros(0)

    @property
    def newest_s(self) -> float | None:
        return float(self._show[-1]) if self._show.size else None

    def next_after(self, show_s: float) -> float | None:
        """The show time of the first kept sample later than ``show_s`` (None: none is)."""
        i = int(np.searchsorted(self._show, show_s, side="right"))
        return float(self._show[i]) if i < self._show.size else None

    def at(self, show_s: float) -> tuple[float, np.ndarray] | None:
        """The latest sample at or before ``show_s`` (the earliest if all are later)."""
        if self._rows is None or self._show.size == 0:
            return None
        i = max(int(np.searchsorted(self._show, show_s, side="right")) - 1, 0)
        return float(self._show[i]), self._rows[i]
