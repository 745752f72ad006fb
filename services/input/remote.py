"""Remote source: another site's input daemon, for a remote jam.

Subscribes (SUB, the one :class:`~services.wire.stream_rx.StreamReceiver`: sequence numbers by the
policy of :mod:`livedrummer.protocol.sequence`) to the remote daemon's event stream and turns
its ONSET/CONTROL messages
back into events, restamped with the local shared clock at arrival: the remote clock is
another machine's, and the local pipeline must see the hit when it arrives here. Every
message is validated by :func:`livedrummer.protocol.decode`; bad ones are dropped, counted
per kind in ``bad`` (a :class:`~services.wire.badmsg.BadMessages`, logged once per kind) and in
total in the problems report. The SUB socket takes every message that starts with the
protocol magic (:func:`~services.wire.net.subscribe_protocol`), so a remote site speaking another
protocol version is counted as such rather than heard as silence; a valid message of a kind
not carried on an events stream (HELLO, READY) is counted as "unexpected". A sequence gap
on the remote stream, or a GAP the remote published, becomes a local GAP with reason
UPSTREAM, so loss stays visible end to end.

Security: with a :class:`~services.wire.net.Security` holding our key pair and the remote
daemon's public key, the SUB socket is a CURVE client (encrypted; refused by a daemon whose
allow folder lacks our key, which looks like silence here).

Timing. Without ``control`` every event is restamped on arrival here, so network jitter shows
in the remote drummer's intervals. With ``control`` (the remote daemon's control endpoint,
``input --remote-control``) the source keeps the sender's timing: it asks that socket for READY
every :data:`PROBE_S` (faster while it starts) and reads the remote clock off the answer's
header, an NTP-style exchange whose offset and drift :class:`~livedrummer.live.clocksync.ClockSync`
estimates with minimum-RTT filtering; every message's transit (arrival minus its send time
mapped onto our clock) feeds a :class:`~livedrummer.live.clocksync.JitterBuffer`, and each event
is held until its own time on the sender's clock, mapped onto ours, plus the buffer's delay,
then released stamped with that time. The intervals between the remote drummer's hits are
kept; the delay (network plus buffer) is logged when it settles or moves by more than
:data:`REPORT_STEP_S`, and summarised at exit (:meth:`RemoteSource.timing`). Until the first
exchange has come back events are restamped on arrival, as without ``control``.

Limits: the remote daemon going away looks like silence (ZeroMQ reconnects by itself);
heartbeats let a caller notice it. An exchange not answered within :data:`PROBE_TIMEOUT_S`
is abandoned with its socket (so a late answer is never taken for the next one's).
"""

from __future__ import annotations

import heapq
import itertools
import logging
from typing import Any

import zmq

from livedrummer.errors import KeyFileError, MidiInputError, ProtocolError
from livedrummer.live.clocksync import ClockSync, JitterBuffer, SyncSample
from livedrummer.protocol import (
    Gap,
    GapReason,
    Hello,
    Kind,
    Message,
    SeqStatus,
    Stream,
    decode,
    encode,
)
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import Control, ControlKind, Onset

from ..wire.net import Security, check_endpoint, connect, socket
from ..wire.stream_rx import StreamReceiver
from .base import Event, Problems, Source

log = logging.getLogger("livedrummer.input")

MAX_BATCH = 1000
EVENT_KINDS = (Kind.ONSET, Kind.CONTROL, Kind.GAP, Kind.HEARTBEAT)
PROBE_S = 1.0  # one clock exchange a second once started ...
FAST_PROBE_S = 0.05  # ... and twenty a second for the first FAST_PROBES
FAST_PROBES = 100
PROBE_TIMEOUT_S = 1.0
REPORT_STEP_S = 0.005


class RemoteSource(Source):
    relayed = True

    def __init__(
        self,
        endpoint: str,
        clock: Clock,
        ctx: zmq.Context[zmq.Socket[bytes]],
        problems: Problems | None = None,
        security: Security | None = None,
        control: str | None = None,
        buffer: JitterBuffer | None = None,
    ) -> None:
        super().__init__(f"remote:{endpoint}", clock, problems)
        self.endpoint = check_endpoint(endpoint, "remote endpoint")
        self.control = None if control is None else check_endpoint(control, "remote control")
        self.ctx = ctx
        self.security = security
        self.rx = StreamReceiver(f"remote {endpoint}", log, EVENT_KINDS)
        self.tracker = self.rx.tracker
        self.bad = self.rx.bad
        self.sync = ClockSync()
        self.buffer = buffer if buffer is not None else JitterBuffer()
        self._probe: Any = None  # DEALER on the remote control socket
        self._probe_sent: float | None = None
        self._probes = 0
        self._next_probe = 0.0
        self._held: list[tuple[float, int, Event]] = []  # (playout time, order, event)
        self._order = itertools.count()
        self._reported: float | None = None

    def open(self) -> None:
        try:
            self.rx.connect(self.ctx, self.endpoint, "remote endpoint", self.security)
        except (ProtocolError, KeyFileError) as exc:
            raise MidiInputError(str(exc)) from exc
        self.is_open = True

    # ------------------------------------------------------------ clock exchanges

    def _send_probe(self, now: float) -> None:
        if self.control is None:
            return
        if self._probe is not None and self._probe_sent is not None:
            if now - self._probe_sent < PROBE_TIMEOUT_S:
                return
            self._probe.close(0)  # unanswered: a late answer must not pair with the next one
            self._probe = None
            self.problems.counts["unanswered clock exchange"] += 1
        if self._probe is None:
            sock = socket(self.ctx, zmq.DEALER)
            try:
                connect(sock, self.control, "remote control", self.security)
            except (ProtocolError, KeyFileError) as exc:
                sock.close(0)
                raise MidiInputError(str(exc)) from exc
            self._probe = sock
        hello = Message(Kind.HELLO, Hello("input", "clock"), stream=Stream.CONTROL)
        self._probe_sent = self.clock.now()
        self._probe.send_multipart([b"", *encode(hello)])
        self._probes += 1
        self._next_probe = now + (FAST_PROBE_S if self._probes < FAST_PROBES else PROBE_S)

    def _take_answer(self) -> None:
        frames = self._probe.recv_multipart()
        received = self.clock.now()
        sent, self._probe_sent = self._probe_sent, None
        try:
            msg = decode(frames[1:] if frames and frames[0] == b"" else frames)
        except ProtocolError as exc:
            self.bad.drop(exc)
            return
        if msg.kind is not Kind.READY or sent is None:
            self.bad.unexpected(msg.kind.name)
            return
        first = not self.sync.ready
        self.sync.add(SyncSample(sent, msg.send_time_s, received))
        if first:
            log.info(
                "%s: remote clock %+.3f ms from ours (first exchange, round trip %.2f ms)",
                self.name,
                1000 * self.sync.offset_at(received),
                1000 * (received - sent),
            )

    def timing(self) -> dict[str, float] | None:
        """Offset, its uncertainty, drift and the playout delay (None before an exchange)."""
        if not self.sync.ready:
            return None
        now = self.clock.now()
        return {
            "offset_ms": 1000 * self.sync.offset_at(now),
            "uncertainty_ms": 1000 * self.sync.uncertainty_s,
            "drift_ppm": 1e6 * self.sync.drift,
            "delay_ms": 1000 * (self.buffer.delay_s or 0.0),
            "late": float(self.buffer.late),
        }

    def _report_delay(self) -> None:
        delay = self.buffer.delay_s
        if delay is None or (
            self._reported is not None and abs(delay - self._reported) < REPORT_STEP_S
        ):
            return
        self._reported = delay
        log.warning(
            "%s: playing the remote drummer %.1f ms behind their clock (network and "
            "jitter buffer; clock offset %+.3f ms +/- %.3f)",
            self.name,
            1000 * delay,
            1000 * self.sync.offset_at(self.clock.now()),
            1000 * self.sync.uncertainty_s,
        )

    # ------------------------------------------------------------ reading

    def read(self, timeout_s: float) -> list[Event]:
        now = self.clock.now()
        if self.control is not None and now >= self._next_probe:
            self._send_probe(now)
        wake = now + timeout_s
        if self._held:
            wake = min(wake, self._held[0][0])
        if self.control is not None:
            wake = min(wake, self._next_probe)
        poller = zmq.Poller()
        poller.register(self.rx.sock, zmq.POLLIN)
        if self._probe is not None:
            poller.register(self._probe, zmq.POLLIN)
        ready = dict(poller.poll(max(0, int((wake - now) * 1000))))
        if self._probe is not None and self._probe in ready:
            self._take_answer()
        out: list[Event] = self._receive() if self.rx.sock in ready else []
        if not self.sync.ready:
            return out
        for event in out:  # timed on the sender's clock: held until their playout time
            when = event.last_time_s if isinstance(event, Gap) else event.time_s
            heapq.heappush(self._held, (when, next(self._order), event))
        released: list[Event] = []
        now = self.clock.now()
        while self._held and self._held[0][0] <= now + 0.0005:
            released.append(self._held[0][2])
            heapq.heappop(self._held)
        self._report_delay()
        return released

    def _timed(self, remote_s: float, now: float) -> float:
        """Our time to play an event stamped ``remote_s`` on the sender's clock (now, before
        the first clock exchange)."""
        if not self.sync.ready:
            return now
        return self.buffer.playout(self.sync.to_local(remote_s), now)

    def _receive(self) -> list[Event]:
        out: list[Event] = []
        batch = self.rx.drain(MAX_BATCH)
        now = self.clock.now()
        if batch.bad:
            self.problems.counts["bad remote message"] += batch.bad
        if batch.duplicates:
            self.problems.report(
                "duplicate remote message", f"{self.name}: {batch.duplicates} dropped"
            )
        for taken in batch.taken:
            msg, seq = taken.msg, taken.seq
            if self.sync.ready:
                self.buffer.observe(now - self.sync.to_local(msg.send_time_s), now)
            if seq.status is SeqStatus.GAP:
                out.append(Gap(seq.missing, now, now, GapReason.UPSTREAM))
                self.problems.report("remote gap", f"{self.name}: {seq.missing} messages lost")
            if msg.kind is Kind.GAP and isinstance(msg.body, Gap):
                out.append(Gap(msg.body.dropped, now, now, GapReason.UPSTREAM))
            elif msg.kind is Kind.ONSET:
                for row in msg.rows:
                    o = Onset.from_record(row)
                    out.append(
                        Onset(
                            self._timed(o.time_s, now),
                            o.note,
                            o.velocity,
                            o.channel,
                            o.instrument,
                            o.zone,
                            o.hihat,
                            o.openness,
                            o.source,
                        )
                    )
            elif msg.kind is Kind.CONTROL:
                for row in msg.rows:
                    out.append(
                        Control(
                            self._timed(float(row["time_s"]), now),
                            ControlKind(int(row["kind"])),
                            int(row["channel"]),
                            int(row["number"]),
                            int(row["value"]),
                            int(row["source"]),
                        )
                    )
        return out

    def close(self) -> None:
        self.rx.close()
        if self._probe is not None:
            self._probe.close(0)
        self._probe = None
        self._probe_sent = None
        self._held.clear()
        self.is_open = False
