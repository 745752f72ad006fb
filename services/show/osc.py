"""OSC show control: a UDP endpoint per service, and ``up``'s one public port in front of them.

Addresses (the table of docs/reference/osc.md):

==============================  ==================  =========================================
``/livedrummer/preset``         name                the synth plays that expression preset
``/livedrummer/param/NAME``     float               one expression parameter (synth)
``/livedrummer/camera``         name or 1-8         smooth move to a stored viewpoint (display)
``/livedrummer/camera/cut``     name or 1-8         cut to it, no move (display)
``/livedrummer/blackout``       0 or 1              fade to black, and back (display)
``/livedrummer/look``           name [fade_s]       the show lights' theme (display)
``/livedrummer/light/L/P``      value(s) [fade_s]   one light parameter (display; L key, fill,
                                                    rim, wash; P intensity, azimuth, elevation,
                                                    r, g, b, enabled 0/1, color r g b or
                                                    "#rrggbb", direction azimuth elevation)
``/livedrummer/cue``            name                a cue of ``--cues FILE`` (both)
``/livedrummer/state``          (none)              reply: name/value pairs of every service
==============================  ==================  =========================================

Why this routing. Each service owns its own show state (the synth its style, the display
its camera and blackout) and applies a command on its own thread and clock, so each runs an
:class:`OscEndpoint` (``synth --osc PORT``, ``display --osc PORT``), a non-blocking UDP socket
that the service's own loop reads between ticks or before each frame (no lock around the
synth or the renderer, no thread waiting for the GIL while a frame is drawn). ``up --osc
PORT`` gives a cue desk one port: :class:`OscRouter` (a thread of ``up``) forwards each
datagram unchanged to the service that serves its address, on loopback ports of their own,
and answers
``/livedrummer/state`` by asking both services and merging their replies. We forward OSC
rather than add message kinds to the ZeroMQ control sockets: those speak the versioned wire
protocol (HELLO/READY), which other work also extends, and a new kind would bump its version
for every peer, while a loopback UDP hop costs a fraction of a millisecond and the services
already parse OSC for their standalone use.

Security. OSC has no authentication: anyone who can send a datagram to the port steers the
show. The endpoint binds 127.0.0.1 unless ``--osc-allow`` lists sender addresses; then it
binds every interface and drops datagrams from any other address (counted as ``sender``).

Bad input. A datagram that is not OSC (``packet``), from a sender not allowed (``sender``),
to an address not served (``address``) or with a wrong argument (``argument``) is dropped,
counted per kind (:class:`~services.wire.badmsg.BadMessages`: logged once per kind) and the show
goes on.

Limits: bundles are unpacked and applied at once (their time tags are ignored); replies go
to the sender's address and port, as OSC clients expect.
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from pythonosc.osc_bundle import OscBundle
from pythonosc.osc_message import OscMessage
from pythonosc.osc_message_builder import OscMessageBuilder

from ..wire.badmsg import BadMessages

PREFIX = "/livedrummer/"
STATE = PREFIX + "state"
CUE = PREFIX + "cue"
SYNTH_ADDRESSES = (PREFIX + "preset", PREFIX + "param/", CUE)
LOOK = PREFIX + "look"
LIGHT = PREFIX + "light/"
DISPLAY_ADDRESSES = (
    PREFIX + "camera",
    PREFIX + "camera/cut",
    PREFIX + "blackout",
    CUE,
    LOOK,
    LIGHT,
)
LOOPBACK = ("127.0.0.1", "::1")
MAX_DATAGRAM = 65_536

Address = tuple[str, int]
Arg = str | float | int | bool


@dataclass(frozen=True)
class Command:
    """One OSC message received: its address, arguments and sender."""

    address: str
    args: tuple[Arg, ...]
    sender: Address


def serves(prefixes: Sequence[str], address: str) -> bool:
    """Whether ``address`` is one of ``prefixes`` (a prefix ending in / takes any tail)."""
    return any(address.startswith(p) if p.endswith("/") else address == p for p in prefixes)


def encode(address: str, args: Iterable[Arg]) -> bytes:
    """One OSC message datagram."""
    b = OscMessageBuilder(address)
    for a in args:
        b.add_arg(a)
    return b.build().dgram


def decode(dgram: bytes) -> list[tuple[str, tuple[Arg, ...]]]:
    """The messages of a datagram (a bundle's, in order); ValueError when it is not OSC."""
    try:
        if OscBundle.dgram_is_bundle(dgram):
            out: list[tuple[str, tuple[Arg, ...]]] = []
            for item in OscBundle(dgram):
                if isinstance(item, OscMessage):
                    out.append((item.address, tuple(item.params)))
                else:
                    out.extend(decode(item.dgram))
            return out
        msg = OscMessage(dgram)
        return [(msg.address, tuple(msg.params))]
    except Exception as exc:  # python-osc raises several kinds on malformed input
        raise ValueError(f"not an OSC packet ({type(exc).__name__}: {exc})") from None


def parse_allow(spec: str | None) -> tuple[str, ...]:
    """``--osc-allow ADDR,...``: sender addresses besides loopback."""
    if not spec:
        return ()
    out = tuple(a.strip() for a in spec.split(",") if a.strip())
    for a in out:
        try:
            socket.inet_pton(socket.AF_INET6 if ":" in a else socket.AF_INET, a)
        except OSError:
            raise ValueError(f"--osc-allow: {a!r} is not an IP address") from None
    return out


def _bind_udp(port: int, allow: Sequence[str], what: str) -> socket.socket:
    host = "0.0.0.0" if allow else "127.0.0.1"
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        from livedrummer.errors import ConfigError

        raise ConfigError(f"{what}: cannot bind UDP {host}:{port}: {exc.strerror}") from None
    sock.settimeout(0.1)
    return sock


def receive(
    sock: socket.socket, allow: frozenset[str], bad: BadMessages
) -> list[tuple[str, tuple[Arg, ...], Address]] | None:
    """One datagram from ``sock``: its messages with their sender, after the sender and
    packet checks (a failed one is counted in ``bad`` and gives []); None when there is
    nothing to read (a non-blocking socket, or a timeout) or the socket is closed. The one
    reading of OSC input, for a service's endpoint and for ``up``'s router."""
    try:
        dgram, sender = sock.recvfrom(MAX_DATAGRAM)
    except (BlockingIOError, InterruptedError, TimeoutError):
        return None
    except OSError as exc:  # e.g. an ICMP error for an earlier reply, or a closed socket
        if sock.fileno() >= 0:
            bad.count("socket", str(exc))
        return None
    if sender[0] not in allow:
        bad.count("sender", f"{sender[0]} is not in --osc-allow")
        return []
    try:
        messages = decode(dgram)
    except ValueError as exc:
        bad.count("packet", str(exc))
        return []
    return [(address, args, (sender[0], int(sender[1]))) for address, args in messages]


class LoopbackSender:
    """OSC messages sent to services' ports on loopback, from one socket of its own (bound,
    so a service's reply comes back to it): ``up``'s router forwards a cue desk's commands
    with it and the MIDI controller bridge sends its commands with it."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sent = 0

    def send(self, port: int, address: str, args: Iterable[Arg]) -> None:
        self.sock.sendto(encode(address, args), ("127.0.0.1", port))
        self.sent += 1

    def close(self) -> None:
        self.sock.close()


class OscEndpoint:
    """A service's OSC port (see the module docstring): :meth:`take` the commands received
    from the service's own loop (between frames or ticks), :meth:`reply` to a sender,
    :meth:`stop`. No thread of its own: a thread would wait for the GIL while the loop
    draws, and the loop reads its other sockets as often anyway."""

    def __init__(
        self,
        port: int,
        serves_: Sequence[str],
        name: str,
        log: logging.Logger,
        allow: Sequence[str] = (),
    ) -> None:
        self.serves = tuple(serves_)
        self.allow = frozenset((*LOOPBACK, *allow))
        self.bad = BadMessages(f"{name} OSC port", log)
        self.received = 0
        self._sock = _bind_udp(port, allow, f"{name} --osc")
        self._sock.setblocking(False)
        self.port = int(self._sock.getsockname()[1])

    def stop(self) -> None:
        self._sock.close()
        self.bad.log_summary()

    def take(self) -> list[Command]:
        """The commands received since the last call, in order (never waits)."""
        out: list[Command] = []
        while (messages := receive(self._sock, self.allow, self.bad)) is not None:
            for address, args, sender in messages:
                if not (address == STATE or serves(self.serves, address)):
                    self.bad.count("address", f"{address} is not served here")
                    continue
                self.received += 1
                out.append(Command(address, args, sender))
        return out

    def reply(self, to: Address, address: str, args: Iterable[Arg]) -> None:
        try:
            self._sock.sendto(encode(address, args), to)
        except OSError as exc:
            self.bad.count("reply", f"cannot answer {to[0]}:{to[1]}: {exc.strerror}")

    def argument(self, cmd: Command, problem: str) -> None:
        """Count a command whose argument is wrong (logged once)."""
        self.bad.count("argument", f"{cmd.address} {list(cmd.args)}: {problem}")


def state_pairs(values: dict[str, Arg]) -> list[Arg]:
    """A state reply's arguments: name, value, name, value, ..."""
    out: list[Arg] = []
    for k, v in values.items():
        out += [k, v]
    return out


class OscRouter:
    """``up``'s public OSC port (see the module docstring): forwards each message to the
    service that serves it and answers ``/livedrummer/state`` from all of them."""

    def __init__(
        self,
        port: int,
        routes: Mapping[str, tuple[Sequence[str], int]],
        log: logging.Logger,
        allow: Sequence[str] = (),
        wait_s: float = 0.5,
    ) -> None:
        self.routes = routes  # service -> (addresses, its loopback OSC port)
        self.allow = frozenset((*LOOPBACK, *allow))
        self.bad = BadMessages("up OSC port", log)
        self.wait_s = wait_s
        self.forwarded = 0
        self._sock = _bind_udp(port, allow, "up --osc")
        self.port = int(self._sock.getsockname()[1])
        self._out = LoopbackSender()
        self._inner = self._out.sock  # the services' state replies come back here
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="up-osc", daemon=True)

    def start(self) -> OscRouter:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(2.0)
        self._sock.close()
        self._out.close()
        self.bad.log_summary()

    def _serve(self) -> None:
        while not self._stop.is_set():
            if self._sock.fileno() < 0:
                return
            for address, args, sender in receive(self._sock, self.allow, self.bad) or ():
                self._route(address, args, sender)

    def _route(self, address: str, args: tuple[Arg, ...], sender: Address) -> None:
        if address == STATE:
            self._sock.sendto(encode(STATE, self._gather()), sender)
            return
        targets = [port for prefixes, port in self.routes.values() if serves(prefixes, address)]
        if not targets:
            self.bad.count("address", f"{address} is not served here")
            return
        for port in targets:
            self._out.send(port, address, args)
        self.forwarded += 1

    def _gather(self) -> list[Arg]:
        """Every service's state reply, merged (a service that does not answer within
        ``wait_s`` is named in ``missing``)."""
        ports = {port: name for name, (_, port) in self.routes.items()}
        while True:  # replies to an earlier request that came too late
            try:
                self._inner.setblocking(False)
                self._inner.recvfrom(MAX_DATAGRAM)
            except OSError:
                break
        self._inner.settimeout(0.05)
        for port in ports:
            self._out.send(port, STATE, ())
        got: dict[str, list[Arg]] = {}
        deadline = time.monotonic() + self.wait_s
        while len(got) < len(ports) and time.monotonic() < deadline:
            try:
                dgram, sender = self._inner.recvfrom(MAX_DATAGRAM)
            except (TimeoutError, BlockingIOError):
                continue
            name = ports.get(int(sender[1]))
            if name is None:
                continue
            try:
                for address, args in decode(dgram):
                    if address == STATE:
                        got[name] = list(args)
            except ValueError:
                continue
        out: list[Arg] = []
        for name in self.routes:
            out += got.get(name, [])
        missing = [n for n in self.routes if n not in got]
        if missing:
            out += ["missing", ",".join(missing)]
        return out
