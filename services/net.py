"""Small ZeroMQ helpers shared by the services: endpoints, socket options, the ready handshake.

Why here. Every service binds or connects a few sockets with the same habits: linger 0 (a
stopping service never hangs on unsent messages), explicit high-water marks (a slow subscriber
costs bounded memory; what ZeroMQ drops beyond the mark shows up as a sequence gap
downstream), and endpoints checked before use so a typo is one line, not a ZMQError. The ready
handshake replaces start-up sleeps: a client sends HELLO on the service's control socket and
the service answers READY only once it is serving (see :mod:`livedrummer.protocol`).

Endpoints are local by default (``tcp://127.0.0.1`` or ``ipc://``); ``tcp://*:PORT`` is
accepted but a service should only bind it with authentication (issue "hardening").
"""

from __future__ import annotations

import re

import zmq

from livedrummer.errors import ProtocolError
from livedrummer.protocol import Hello, Kind, Message, Stream, decode, encode

DEFAULT_HWM = 100_000
_ENDPOINT = re.compile(r"^(tcp://[^\s:/]+:(\d+|\*)|ipc://\S+|inproc://\S+)$")


def check_endpoint(text: str, what: str = "endpoint") -> str:
    """Return ``text`` if it is a usable ZeroMQ endpoint, else raise a named error."""
    if not _ENDPOINT.match(text):
        raise ProtocolError(
            f"{what}: {text!r} is not a ZeroMQ endpoint "
            "(expected tcp://HOST:PORT, tcp://HOST:*, ipc://PATH or inproc://NAME)"
        )
    m = re.match(r"^tcp://[^:]+:(\d+)$", text)
    if m and not 0 < int(m.group(1)) < 65536:
        raise ProtocolError(f"{what}: port {m.group(1)} out of range in {text!r}")
    return text


def socket(
    ctx: zmq.Context[zmq.Socket[bytes]], kind: int, hwm: int = DEFAULT_HWM
) -> zmq.Socket[bytes]:
    sock = ctx.socket(kind)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.SNDHWM, hwm)
    sock.setsockopt(zmq.RCVHWM, hwm)
    return sock


def bind(sock: zmq.Socket[bytes], endpoint: str, what: str) -> str:
    """Bind and return the real endpoint (the OS-chosen port for ``tcp://HOST:*``)."""
    check_endpoint(endpoint, what)
    try:
        sock.bind(endpoint)
    except zmq.ZMQError as exc:
        raise ProtocolError(f"{what}: cannot bind {endpoint}: {exc}") from exc
    last = sock.getsockopt(zmq.LAST_ENDPOINT)
    return last.decode() if isinstance(last, bytes) else str(last)


def connect(sock: zmq.Socket[bytes], endpoint: str, what: str) -> None:
    check_endpoint(endpoint, what)
    try:
        sock.connect(endpoint)
    except zmq.ZMQError as exc:
        raise ProtocolError(f"{what}: cannot connect to {endpoint}: {exc}") from exc


def request_ready(
    ctx: zmq.Context[zmq.Socket[bytes]],
    endpoint: str,
    hello: Hello,
    timeout_s: float,
) -> Hello:
    """Send HELLO to a service's control socket and wait (bounded) for its READY."""
    sock = socket(ctx, zmq.DEALER)
    try:
        connect(sock, endpoint, "control endpoint")
        sock.send_multipart([b"", *encode(Message(Kind.HELLO, hello, stream=Stream.CONTROL))])
        if not sock.poll(int(timeout_s * 1000)):
            raise ProtocolError(f"{endpoint}: no READY within {timeout_s:g} s")
        frames = sock.recv_multipart()
        msg = decode(frames[1:] if frames and frames[0] == b"" else frames)
        if msg.kind is not Kind.READY or not isinstance(msg.body, Hello):
            raise ProtocolError(f"{endpoint}: answered {msg.kind.name}, expected READY")
        return msg.body
    finally:
        sock.close(0)
