"""How far ahead of its show time a live frame must be started: the display's own latency.

A frame rendered at clock time ``c`` is seen when it is finished (off screen: written; in a
window: presented), not at ``c``. The live display therefore draws the pose for
``c + audio latency + render latency``, where the render latency is measured on the frames
it has just drawn: a high quantile (default 0.99) of the last ``window`` frames' start-to-done
times, so nine frames in ten are finished by the moment they show and the estimate follows a
change of load, window size or machine within a second. Until the first frame is done the
estimate is 0.
"""

from __future__ import annotations

from collections import deque

import numpy as np


class RenderAhead:
    """Rolling estimate of the time from starting a frame to its being seen."""

    def __init__(self, window: int = 120, quantile: float = 0.99, limit_s: float = 0.1) -> None:
        if not 0.0 < quantile <= 1.0 or window < 1:
            raise ValueError(f"need window >= 1 and 0 < quantile <= 1, got {window}, {quantile}")
        self._done: deque[float] = deque(maxlen=window)
        self._q = quantile * 100.0
        self._limit = limit_s  # a stalled frame (a window dragged, a debugger) is not a norm
        self._value = 0.0

    def add(self, seconds: float) -> None:
        """One frame's start-to-done time."""
        self._done.append(min(max(seconds, 0.0), self._limit))
        self._value = float(np.percentile(np.fromiter(self._done, float), self._q))

    @property
    def seconds(self) -> float:
        return self._value
