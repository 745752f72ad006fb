"""The kit's hits read from an input daemon's onset stream, for the practice rig with a window.

When the practice rig shows the player's drummer, the input daemon owns the kit's port (as in
``up``: input → synth → display), so the rig cannot open it too. It subscribes to the daemon's
stream instead, like the synth does: :class:`OnsetBus` has the calls the rig makes of a kit
source (``open``, ``read``, ``close``, ``decode_stats``) and yields each ONSET row as an
:class:`~livedrummer.timeline.events.Onset` with the daemon's time stamp, the driver's stamp on
the shared clock, unchanged, so a hit is judged at the same time as when the rig reads the port
itself. The rig connects before it starts the daemon, and the daemon waits for its subscribers
(``input --wait-subscribers``), so no hit is published before the rig listens.

Bad input: the stream is read by the one :class:`~services.wire.stream_rx.StreamReceiver`; a
message that does not decode, or is not an onset, control, gap or heartbeat, is counted and
logged (:class:`~services.wire.badmsg.BadMessages`), never fatal; a gap in the sequence numbers
(hits lost on the way) is counted in :attr:`OnsetBus.missing` and logged, a restarted daemon
is taken and a duplicate dropped (:mod:`livedrummer.protocol.sequence`).

Limits: the daemon decodes notes with its ``--map`` (the rig passes its ``--take-map``), so the
rig cannot list the notes that map does not know (``decode_stats`` is None; the daemon logs
them).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import zmq

from livedrummer.protocol import Kind
from livedrummer.timeline.events import Onset

from ..wire.stream_rx import StreamReceiver

log = logging.getLogger("livedrummer.practice")
_KINDS = (Kind.ONSET, Kind.CONTROL, Kind.GAP, Kind.HEARTBEAT)


class OnsetBus:
    """See the module docstring."""

    def __init__(self, ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str) -> None:
        self.endpoint = endpoint
        self.rx = StreamReceiver("practice: input stream", log, _KINDS)
        self.bad = self.rx.bad
        self.missing = 0
        self.onsets = 0
        self.rx.connect(ctx, endpoint, "input endpoint")

    def open(self) -> None:
        """Connected already (see the module docstring)."""

    def read(self, timeout_s: float) -> list[Onset]:
        """The hits that arrived, waiting up to ``timeout_s`` for the first."""
        out: list[Onset] = []
        if not self.rx.poll(int(timeout_s * 1000)):
            return out
        batch = self.rx.drain()
        self.missing += batch.missing
        for msg in batch.messages:
            if msg.kind is Kind.ONSET and isinstance(msg.body, np.ndarray):
                out.extend(Onset.from_record(row) for row in msg.body)
                self.onsets += len(msg.body)
        return out

    def close(self) -> None:
        self.rx.close()

    def decode_stats(self) -> Any:
        return None
