"""The practice rig's readout stream to its display: one JSON object a message, on loopback.

The rig (``livedrummer practice`` with a window) binds a PUB socket on 127.0.0.1 at a port the
system picks and passes it to its display (``display --live --practice ENDPOINT``), which draws
the readout and moves the teacher (:mod:`services.display.practice_view`). Three messages:

* ``{"plan": {pass, start_s, scale, bpm, bars, seg_start_s, seg_end_s, window_ms, level_ms,
  teacher}}``: a pass planned (``start_s`` on the shared clock; the segment in reference
  seconds), sent when the rig plans it;
* ``{"hit": {pass, time_s, piece, offset_ms, on_time, streak, accuracy_pct}}``: a hit's
  provisional line, as the terminal prints it (:mod:`livedrummer.practice.live`);
* ``{"summary": {pass, lines, result}}``: a pass judged, its summary lines and result object.

JSON because the messages are few (a hit a beat) and small, and a person can read them with
any ZMQ tool; the display counts what it cannot read. Plans are sent again every
:data:`REPEAT_S` while they are due, so a display that (re)connected late still gets them
(the display keeps one pass per start time).
"""

from __future__ import annotations

import json
from typing import Any

import zmq

from ..wire.net import bind, socket

REPEAT_S = 1.0


class ReadoutOut:
    """See the module docstring."""

    def __init__(self, ctx: zmq.Context[zmq.Socket[bytes]]) -> None:
        self._pub = socket(ctx, zmq.PUB)
        self.endpoint = bind(self._pub, "tcp://127.0.0.1:*", "practice readout endpoint")
        self.plans: list[dict[str, Any]] = []
        self._repeat_at = 0.0

    def send(self, obj: dict[str, Any]) -> None:
        if "plan" in obj:
            self.plans.append(obj)
        self._pub.send(json.dumps(obj).encode())

    def tick(self, now_s: float) -> None:
        """Send again the plans of passes not over yet (see the module docstring)."""
        if now_s < self._repeat_at:
            return
        self._repeat_at = now_s + REPEAT_S
        for obj in self.plans:
            p = obj["plan"]
            if now_s < p["start_s"] + (p["seg_end_s"] - p["seg_start_s"]) / p["scale"]:
                self._pub.send(json.dumps({"plan_again": p}).encode())

    def close(self) -> None:
        self._pub.close(0)
