"""The relay: one synth's pose stream fanned out to many displays, over several machines.

Why. A synth publishes its poses on one PUB socket; every display connected to it costs the
synth one more copy of each message on its own machine's uplink and one more TCP peer in the
process that must also answer hits within a few milliseconds. For an audience beyond one
machine (a wall of screens, a theatre's projectors, a remote venue) displays connect to a
relay instead: ``livedrummer relay --upstream SYNTH_PUB`` subscribes once upstream and
republishes each message byte for byte to its own subscribers. Relays chain into a tree (a
relay's upstream may be another relay), so the synth's cost stays one subscriber however
many screens there are.

Shape. :class:`RelayService` is a :class:`~services.process.service.Service` (the shared life cycle:
control socket, CURVE, shutdown) whose job is a forwarding loop between an XSUB socket
connected upstream and an XPUB socket bound for displays. Subscriptions travel up (a display's
subscription reaches the synth through every relay on the way, so nothing flows where nobody
listens) and messages travel down untouched: the relay does not decode them, so it adds no
copy of the payload beyond ZeroMQ's own and needs no pose format of its own. Displays keep
their per-performer sequence numbers, since the header is the synth's. The relay asks the
upstream's control socket for its READY once at start (``--upstream-control``) and answers
HELLO on its own control socket with that READY's pose format, performer and avatar digest
under its own endpoints, so ``display --live --sub RELAY --synth-control RELAY_CONTROL``
works as it does against a synth. It is ready (systemd, launchers) once its sockets are up:
a relay with no listeners has nothing to forward, and that is not a fault.

Security: with ``--curve-secret`` its XPUB and control sockets are CURVE servers (``--allow``
for a list of displays), with ``--server-key`` its upstream connection is a CURVE client of
the synth or the relay above; see :mod:`services.wire.net`.

Limits: a slow display loses messages past the XPUB's high-water mark (it sees the gap in
the sequence numbers, as it would on the synth); the relay does not re-ask the upstream's
READY when the synth restarts with another avatar (the displays' own check against a synth
control socket does); one upstream per relay.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field
from typing import Any

import zmq

from livedrummer.protocol import Hello

from ..process.service import OnReady, Service
from ..wire.net import Security, bind, connect, request_ready, socket

log = logging.getLogger("livedrummer.relay")

DEFAULT_PUB = "tcp://127.0.0.1:5820"
DEFAULT_CONTROL = "tcp://127.0.0.1:5821"
READY_TIMEOUT_S = 5.0


@dataclass
class RelayConfig:
    upstream: str
    upstream_control: str | None = None
    pub: str = DEFAULT_PUB
    control: str | None = DEFAULT_CONTROL
    security: Security = field(default_factory=Security)


@dataclass
class RelayStats:
    messages: int = 0
    bytes: int = 0
    subscriptions: int = 0  # subscribe messages seen from displays (one per display and topic)
    unsubscriptions: int = 0


class RelayService(Service):
    """See the module docstring."""

    name = "relay"

    def __init__(
        self, config: RelayConfig, clock: Any, ctx: zmq.Context[zmq.Socket[bytes]]
    ) -> None:
        super().__init__(clock, ctx, security=config.security, control=config.control, log=log)
        self.config = config
        self.stats = RelayStats()
        self.upstream: Hello | None = None
        self._xsub: Any = None
        self._xpub: Any = None

    def open(self) -> None:
        cfg = self.config
        if cfg.upstream_control is not None:
            self.upstream = request_ready(
                self.ctx,
                cfg.upstream_control,
                Hello(self.name, "poses"),
                READY_TIMEOUT_S,
                cfg.security,
            )
            self.performer = self.upstream.performer
        self._xsub = socket(self.ctx, zmq.XSUB)
        self._xpub = socket(self.ctx, zmq.XPUB)
        connect(self._xsub, cfg.upstream, "upstream endpoint", cfg.security)
        self.endpoints["upstream"] = cfg.upstream
        self.endpoints["pub"] = bind(self._xpub, cfg.pub, "pub endpoint", cfg.security)

    def release(self) -> None:
        for sock in (self._xsub, self._xpub):
            if sock is not None:
                sock.close(0)
        self._xsub = self._xpub = None

    def hello(self) -> Hello:
        up = self.upstream
        pose, avatar = (None, "") if up is None else (up.pose, up.avatar)
        return Hello(self.name, "poses", self.performer, dict(self.endpoints), pose, avatar=avatar)

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        """Forward until ``stop``: messages down, subscriptions up."""
        xsub, xpub, stats = self._xsub, self._xpub, self.stats
        poller = zmq.Poller()
        poller.register(xsub, zmq.POLLIN)
        poller.register(xpub, zmq.POLLIN)
        if on_ready is not None:
            on_ready()
        try:
            while not stop.is_set():
                events = dict(poller.poll(100))
                if xsub in events:  # drain what is queued: one poll per burst, not per message
                    while True:
                        try:
                            frames = xsub.recv_multipart(zmq.NOBLOCK, copy=False)
                        except zmq.Again:
                            break
                        xpub.send_multipart(frames, copy=False)
                        stats.messages += 1
                        stats.bytes += sum(len(f.buffer) for f in frames)
                if xpub in events:
                    while True:
                        try:
                            sub = xpub.recv(zmq.NOBLOCK)
                        except zmq.Again:
                            break
                        if sub[:1] == b"\x01":
                            stats.subscriptions += 1
                        elif sub[:1] == b"\x00":
                            stats.unsubscriptions += 1
                        xsub.send(sub)
        finally:
            self.shutdown()
        return 0

    def summary(self) -> dict[str, int]:
        s = self.stats
        return {
            "messages": s.messages,
            "bytes": s.bytes,
            "subscriptions": s.subscriptions,
            "unsubscriptions": s.unsubscriptions,
        }
