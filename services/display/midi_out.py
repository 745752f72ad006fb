"""``display FILE --midi-out PORT``: the file's drums sent to an external sampler as the window
plays them, in step with the picture.

The window tells :meth:`MidiFileOut.follow` each frame where its transport is ("position
``t`` at monotonic time ``m``, rolling or not"), as it tells the sound player. A thread of
its own sends each onset's note (the file's own note and channel, note-on then note-off at
once: drums are one-shots) at ``m + (onset - t)``, sleeping until then, so a note leaves on
time to the millisecond rather than on the next frame. A jump (seek, step, marker, the
start) moves the next note to send to the first onset at or after the new position; pause,
other speeds and reverse send nothing (the window says so, as for its sound). The port is an
existing MIDI input port (a sampler's; exact name or unique substring) or, where none
matches, a virtual output port of that name (:class:`~services.input.thru.MidiThru`).

The window's ``m`` is when the frame it is about to draw will be seen (its median time to
draw and swap later, as for the sound), so a note leaves when the picture of its contact
shows. Limits: the sampler's own latency is not known here (an external sampler adds its
buffer); a frame that takes much longer than the median is seen after its notes.
"""

from __future__ import annotations

import logging
import threading
import time

import numpy as np

from ..input.thru import MidiThru

log = logging.getLogger("livedrummer.display")
JUMP_S = 0.02  # a request this far from where the sender is moves it
POLL_S = 0.005  # the sender looks at the window's requests at least this often


class MidiFileOut:
    """See the module docstring."""

    def __init__(self, onsets: np.ndarray, port: str, api: str = "auto") -> None:
        order = np.argsort(onsets["time_s"], kind="stable")
        self.times = onsets["time_s"][order].astype(np.float64)
        self.notes = onsets["note"][order].astype(int)
        self.velocities = onsets["velocity"][order].astype(int)
        self.channels = onsets["channel"][order].astype(int)
        self.out = MidiThru(port, api, what="midi-out")
        self.sent = 0
        self._request: tuple[float, float, bool] | None = None  # (position, at, rolling)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="midi-out", daemon=True)
        self._thread.start()

    def follow(self, position_s: float, at: float, rolling: bool) -> None:
        """At monotonic time ``at`` the transport is at ``position_s``; send if ``rolling``."""
        with self._lock:
            self._request = (position_s, at, rolling)

    def _run(self) -> None:
        anchor: tuple[float, float] | None = None  # (position, at) the sender keeps to
        k = 0
        while not self._stop.is_set():
            with self._lock:
                request = self._request
            now = time.monotonic()
            if request is None or not request[2]:
                anchor = None
                time.sleep(POLL_S)
                continue
            position_now = request[0] + (now - request[1])
            if anchor is None or abs(anchor[0] + (now - anchor[1]) - position_now) > JUMP_S:
                anchor = (request[0], request[1])  # a jump, or the start: from here on
                k = int(np.searchsorted(self.times, position_now - 1e-9, side="left"))
            if k >= self.times.size:
                time.sleep(POLL_S)
                continue
            due = anchor[1] + (float(self.times[k]) - anchor[0])
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(min(wait, POLL_S))
                continue
            status = 0x90 | int(self.channels[k])
            self.out.send([status, int(self.notes[k]), max(1, int(self.velocities[k]))])
            self.out.send([0x80 | int(self.channels[k]), int(self.notes[k]), 0])
            self.sent += 1
            k += 1

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self.out.close()
