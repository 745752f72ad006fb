"""The kit's hits read from an input daemon's onset stream, for the practice rig with a window.

When the practice rig shows the player's drummer, the input daemon owns the kit's port (as in
``up``: input → synth → display), so the rig cannot open it too. It subscribes to the daemon's
stream instead, like the synth does: :class:`OnsetBus` has the calls the rig makes of a kit
source (``open``, ``read``, ``close``, ``decode_stats``) and yields each ONSET row as an
:class:`~livedrummer.timeline.events.Onset` with the daemon's time stamp, the driver's stamp on
the shared clock, unchanged, so a hit is judged at the same time as when the rig reads the port
itself. The rig connects before it starts the daemon, and the daemon waits for its subscribers
(``input --wait-subscribers``), so no hit is published before the rig listens.

Bad input: a message that does not decode, or is not an onset, control, gap or heartbeat, is
counted and logged (:class:`~services.badmsg.BadMessages`), never fatal; a gap in the sequence
numbers (hits lost on the way) is counted in :attr:`OnsetBus.missing`.

Limits: the daemon decodes notes with its ``--map`` (the rig passes its ``--take-map``), so the
rig cannot list the notes that map does not know (``decode_stats`` is None; the daemon logs
them).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import zmq

from livedrummer.errors import ProtocolError
from livedrummer.protocol import Kind, SeqStatus, SequenceTracker, decode
from livedrummer.timeline.events import Onset

from ..badmsg import BadMessages
from ..net import connect, socket, subscribe_protocol

log = logging.getLogger("livedrummer.practice")
_KINDS = (Kind.ONSET, Kind.CONTROL, Kind.GAP, Kind.HEARTBEAT)


class OnsetBus:
    """See the module docstring."""

    def __init__(self, ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str) -> None:
        self.endpoint = endpoint
        self.bad = BadMessages("practice: input stream", log)
        self.tracker = SequenceTracker()
        self.missing = 0
        self.onsets = 0
        self._sub = socket(ctx, zmq.SUB)
        subscribe_protocol(self._sub)
        connect(self._sub, endpoint, "input endpoint")

    def open(self) -> None:
        """Connected already (see the module docstring)."""

    def read(self, timeout_s: float) -> list[Onset]:
        """The hits that arrived, waiting up to ``timeout_s`` for the first."""
        out: list[Onset] = []
        if not self._sub.poll(int(timeout_s * 1000)):
            return out
        while True:
            try:
                frames = self._sub.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                return out
            try:
                msg = decode(frames)
            except ProtocolError as exc:
                self.bad.drop(exc)
                continue
            if msg.kind not in _KINDS:
                self.bad.unexpected(msg.kind.name)
                continue
            report = self.tracker.observe_message(msg)
            if report.status is SeqStatus.GAP:
                self.missing += report.missing
                log.warning("practice: %d input messages lost", report.missing)
            if msg.kind is Kind.ONSET and isinstance(msg.body, np.ndarray):
                out.extend(Onset.from_record(row) for row in msg.body)
                self.onsets += len(msg.body)

    def close(self) -> None:
        self._sub.close(0)
        self.bad.log_summary()

    def decode_stats(self) -> Any:
        return None
