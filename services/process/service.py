"""One life cycle for every livedrummer process: start, ready, control socket, shutdown.

Why a base. The input daemon, the synth and the live display each bind or connect a few
sockets, may run a ZAP authenticator, answer HELLO with READY on a ROUTER control socket
from a thread of their own, tell a launcher or systemd when they are serving, stop on
SIGTERM/SIGINT and close everything in the right order, including after a start that failed
half way. That was written three times, each with its own cleanup ladder. Here it is once:

* :class:`Service` holds what they share: clock, ZeroMQ context, performer, security,
  endpoints, the control socket and its thread, the authenticator, the control socket's bad
  message counts. A service implements :meth:`Service.open` (its own sockets and files,
  stored on ``self`` *before* they are bound, so that a failure part way is cleaned up by
  :meth:`Service.release`), :meth:`Service.release` (idempotent), :meth:`Service.hello`
  and :meth:`Service.run`. :meth:`Service.start` runs the authenticator, ``open`` and the
  control socket, and on any failure shuts down what was opened before re-raising;
  :meth:`Service.shutdown` stops the control thread, releases, stops the authenticator and
  logs the totals, once, however often it is called.
* :func:`serve` is the process around a service: signal handlers, the one JSON line of
  endpoints on stdout that launchers and tests read, the readiness notification
  (:mod:`services.process.notify`), given by the service through ``on_ready`` when it *does its job*
  (the daemon once bound, the synth after its first poses, the display after its first frame
  with the drummer), and the context's termination.

Limits: one control socket per service; the control thread polls every 100 ms, so shutdown
takes up to that long; READY is answered from the control thread, so ``hello()`` must only
read state that is safe to read from another thread (endpoints, formats, digests).
"""

from __future__ import annotations

import json
import logging
import signal
import threading
from collections.abc import Callable, Mapping
from types import FrameType
from typing import Any, Protocol

import zmq

from livedrummer.protocol import Hello, Kind, Message, Stream

from ..wire.badmsg import BadMessages
from ..wire.net import Security, bind, serve_control, socket, start_authenticator
from .notify import ready

OnReady = Callable[[], None]


class Now(Protocol):
    """What the base reads from a service's clock (a shared clock or a display's frame clock)."""

    def now(self) -> float: ...


class Service:
    """The shared life cycle (see the module docstring); subclasses do their own job."""

    #: Service name in HELLO/READY and in the JSON line ("input", "synth", "display").
    name = "service"

    def __init__(
        self,
        clock: Now,
        ctx: zmq.Context[zmq.Socket[bytes]],
        *,
        performer: int = 0,
        security: Security | None = None,
        control: str | None = None,
        log: logging.Logger | None = None,
    ) -> None:
        self.clock = clock
        self.ctx = ctx
        self.performer = performer
        self.security = security or Security()
        self.control_endpoint = control
        self.log = log or logging.getLogger(f"livedrummer.{self.name}")
        self.endpoints: dict[str, str] = {}
        self.bad_control = BadMessages(f"{self.name} control socket", self.log)
        self._control_stop = threading.Event()
        self._control_thread: threading.Thread | None = None
        self._control: Any = None  # the control socket until its thread owns it
        self._auth: Any = None
        self._down = False

    # ------------------------------------------------------------ what a service provides

    def open(self) -> None:
        """Bind/connect the service's own sockets, open its files; fill ``self.endpoints``."""

    def release(self) -> None:
        """Close what :meth:`open` opened (idempotent; also after a failed ``open``)."""

    def hello(self) -> Hello:
        return Hello(self.name, "", self.performer, dict(self.endpoints))

    def control_dropped(self, kind: str) -> None:
        """Called with the kind of every bad message on the control socket (counted already)."""

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        """Serve until ``stop``; call ``on_ready`` once when serving; shut down at the end."""
        raise NotImplementedError

    # ------------------------------------------------------------ the shared life cycle

    def start(self) -> dict[str, str]:
        """Authenticator, control socket, :meth:`open`, control thread; undone on failure.

        The control socket is bound before :meth:`open`, so a service's ``open`` (the input
        daemon's journal header) already sees every endpoint; it is answered only once
        ``open`` succeeded.
        """
        self._down = False
        try:
            if self.security.allow is not None:
                self._auth = start_authenticator(self.ctx, self.security.allow)
            if self.control_endpoint is not None:
                self._control = socket(self.ctx, zmq.ROUTER)
                self.endpoints["control"] = bind(
                    self._control, self.control_endpoint, "control endpoint", self.security
                )
            self.open()
            if self._control is not None:
                self._control_stop.clear()
                self._control_thread = threading.Thread(
                    target=serve_control,
                    args=(
                        self._control,
                        self._control_stop,
                        self.ready_message,
                        self.bad_control,
                        self.control_dropped,
                    ),
                    name=f"{self.name}-control",
                    daemon=True,
                )
                self._control = None  # the thread owns it now and closes it when stopped
                self._control_thread.start()
        except BaseException:
            self.shutdown()
            raise
        return dict(self.endpoints)

    def ready_message(self) -> Message:
        """The READY a HELLO on the control socket is answered with."""
        return Message(
            Kind.READY, self.hello(), self.performer, 0, self.clock.now(), Stream.CONTROL
        )

    def shutdown(self) -> None:
        """Stop the control thread, release, stop the authenticator, log totals (once)."""
        if self._down:
            return
        self._down = True
        self._control_stop.set()
        if self._control_thread is not None:
            self._control_thread.join(2.0)
            self._control_thread = None
        if self._control is not None:
            self._control.close(0)
            self._control = None
        try:
            self.release()
        finally:
            if self._auth is not None:
                self._auth.stop()
                self._auth = None
            self.bad_control.log_summary()


def serve(
    service: Service,
    notify_detail: Callable[[dict[str, str]], str] | None = None,
    facts: Mapping[str, object] | None = None,
) -> int:
    """Run ``service`` as this process: signals, endpoints line, readiness, context end.

    Prints ``{"service": NAME, **endpoints, **facts}`` on stdout once bound (``facts``: what
    else a launcher reads there, such as the settings the service plays with), tells a launcher or
    systemd the service is ready when the service says so (``notify_detail(endpoints)`` is the
    detail sent, by default the first endpoint), stops on SIGTERM/SIGINT and terminates the
    ZeroMQ context whatever happens. Returns the service's exit status.
    """
    stop = threading.Event()

    def on_signal(signum: int, _frame: FrameType | None) -> None:
        stop.set()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    try:
        endpoints = service.start()
        print(json.dumps({"service": service.name, **endpoints, **(facts or {})}), flush=True)
        detail = (
            notify_detail(endpoints)
            if notify_detail is not None
            else next(iter(endpoints.values()), "")
        )
        return service.run(stop, on_ready=lambda: ready(detail))
    finally:
        service.shutdown()
        service.ctx.term()
