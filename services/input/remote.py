"""Remote source: another site's input daemon, for a remote jam.

Subscribes (SUB) to the remote daemon's event stream and turns its ONSET/CONTROL messages
back into events, restamped with the local shared clock at arrival: the remote clock is
another machine's, and the local pipeline must see the hit when it arrives here. Every
message is validated by :func:`livedrummer.protocol.decode`; bad ones are dropped, counted
per kind in ``bad`` (a :class:`~services.badmsg.BadMessages`, logged once per kind) and in
total in the problems report. The SUB socket takes every message that starts with the
protocol magic (:func:`~services.net.subscribe_protocol`), so a remote site speaking another
protocol version is counted as such rather than heard as silence; a valid message of a kind
not carried on an events stream (HELLO, READY) is counted as "unexpected". A sequence gap
on the remote stream, or a GAP the remote published, becomes a local GAP with reason
UPSTREAM, so loss stays visible end to end.

Security: with a :class:`~services.net.Security` holding our key pair and the remote
daemon's public key, the SUB socket is a CURVE client (encrypted; refused by a daemon whose
allow folder lacks our key, which looks like silence here).

Limits: no clock-offset estimation between sites. The remote daemon going away looks like silence
(ZeroMQ reconnects by itself); heartbeats let a caller notice it.
"""

from __future__ import annotations

import logging
from typing import Any

import zmq

from livedrummer.errors import KeyFileError, MidiInputError, ProtocolError
from livedrummer.protocol import Gap, GapReason, Kind, SeqStatus, SequenceTracker, decode
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import Control, ControlKind, Onset

from ..badmsg import BadMessages
from ..net import Security, check_endpoint, connect, socket, subscribe_protocol
from .base import Event, Problems, Source

log = logging.getLogger("livedrummer.input")

MAX_BATCH = 1000
EVENT_KINDS = (Kind.ONSET, Kind.CONTROL, Kind.GAP, Kind.HEARTBEAT)


class RemoteSource(Source):
    relayed = True

    def __init__(
        self,
        endpoint: str,
        clock: Clock,
        ctx: zmq.Context[zmq.Socket[bytes]],
        problems: Problems | None = None,
        security: Security | None = None,
    ) -> None:
        super().__init__(f"remote:{endpoint}", clock, problems)
        self.endpoint = check_endpoint(endpoint, "remote endpoint")
        self.ctx = ctx
        self.security = security
        self.tracker = SequenceTracker()
        self.bad = BadMessages(f"remote {endpoint}", log)
        self._sock: Any = None

    def open(self) -> None:
        sock = socket(self.ctx, zmq.SUB)
        try:
            subscribe_protocol(sock)
            connect(sock, self.endpoint, "remote endpoint", self.security)
        except (ProtocolError, KeyFileError) as exc:
            sock.close(0)
            raise MidiInputError(str(exc)) from exc
        self._sock = sock
        self.is_open = True

    def read(self, timeout_s: float) -> list[Event]:
        out: list[Event] = []
        if not self._sock.poll(int(timeout_s * 1000)):
            return out
        for _ in range(MAX_BATCH):
            try:
                frames = self._sock.recv_multipart(zmq.NOBLOCK)
            except zmq.Again:
                break
            now = self.clock.now()
            try:
                msg = decode(frames)
            except ProtocolError as exc:
                self.bad.drop(exc)
                self.problems.counts["bad remote message"] += 1
                continue
            if msg.kind not in EVENT_KINDS:
                self.bad.unexpected(msg.kind.name)
                self.problems.counts["bad remote message"] += 1
                continue
            seq = self.tracker.observe_message(msg)
            if seq.status is SeqStatus.DUPLICATE:
                self.problems.report("duplicate remote message", f"{self.name}: seq {msg.seq}")
                continue
            if seq.status is SeqStatus.GAP:
                out.append(Gap(seq.missing, now, now, GapReason.UPSTREAM))
                self.problems.report("remote gap", f"{self.name}: {seq.missing} messages lost")
            if msg.kind is Kind.GAP and isinstance(msg.body, Gap):
                out.append(Gap(msg.body.dropped, now, now, GapReason.UPSTREAM))
            elif msg.kind is Kind.ONSET:
                for row in msg.rows:
                    o = Onset.from_record(row)
                    out.append(
                        Onset(now, o.note, o.velocity, o.channel, o.instrument, o.zone,
                              o.hihat, o.openness, o.source)
                    )  # fmt: skip
            elif msg.kind is Kind.CONTROL:
                for row in msg.rows:
                    out.append(
                        Control(now, ControlKind(int(row["kind"])), int(row["channel"]),
                                int(row["number"]), int(row["value"]), int(row["source"]))
                    )  # fmt: skip
        return out

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close(0)
            self._sock = None
        self.is_open = False
