"""Small ZeroMQ helpers shared by the services: endpoints, socket options, the ready handshake.

Why here. Every service binds or connects a few sockets with the same habits: linger 0 (a
stopping service never hangs on unsent messages), explicit high-water marks (a slow subscriber
costs bounded memory; what ZeroMQ drops beyond the mark shows up as a sequence gap
downstream), and endpoints checked before use so a typo is one line, not a ZMQError. Every
socket also refuses inbound frames above :data:`MAX_FRAME` (twice the protocol's payload
limit): ZeroMQ closes that connection rather than buffer a gigabyte from a broken peer, and
anything smaller but still too large reaches :func:`~livedrummer.protocol.decode`, which
refuses it by name (receivers count such drops with :mod:`services.wire.badmsg`). The ready
handshake replaces start-up sleeps: a client sends HELLO on the service's control socket and
the service answers READY only once it is serving (see :mod:`livedrummer.protocol`).

Security. Endpoints are local by default (``tcp://127.0.0.1`` or ``ipc://``). A remote
stream uses ZeroMQ CURVE: a bound socket given our secret key becomes a CURVE server
(:func:`curve_server`), a connecting socket given our secret key and the server's public
key a CURVE client (:func:`curve_client`); traffic is then encrypted and the client must
know the server's key. With an allow folder (public ``.key`` files of the peers we trust),
:func:`start_authenticator` runs pyzmq's ZAP authenticator in the context, and a client
whose key is not there never completes its handshake (it receives nothing). :func:`bind`
refuses a non-loopback TCP address unless the socket is a CURVE server or the caller said
``insecure`` explicitly. Limits: one authenticator per context (one allow folder per
process); the allow folder is read at start, so a key added later needs a restart; plain
(NULL) sockets in the same context are not checked by it.
"""

from __future__ import annotations

import logging
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import zmq
from zmq.auth.thread import ThreadAuthenticator

from livedrummer.errors import KeyFileError, ProtocolError
from livedrummer.protocol import (
    MAGIC,
    MAX_PAYLOAD,
    Hello,
    Kind,
    Message,
    Stream,
    decode,
    encode,
)
from livedrummer.protocol.keys import KeyPair, read_key_file

from .badmsg import BadMessages

DEFAULT_HWM = 100_000
MAX_FRAME = 2 * MAX_PAYLOAD
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
    sock.setsockopt(zmq.MAXMSGSIZE, MAX_FRAME)
    return sock


_LOOPBACK_HOSTS = ("localhost", "::1", "[::1]")


@dataclass(frozen=True)
class Security:
    """CURVE settings of one service: our key pair, the server's key, the allow folder.

    ``secret`` makes bound sockets CURVE servers and, with ``server_public``, connecting
    sockets CURVE clients. ``allow`` names the folder of public ``.key`` files of the
    clients let in (None: any client that knows our public key). ``insecure`` allows a
    plain bind on a non-loopback address.
    """

    secret: KeyPair | None = None
    server_public: bytes | None = None
    allow: Path | None = None
    insecure: bool = False

    @classmethod
    def from_files(
        cls,
        secret: Path | None = None,
        server_key: Path | None = None,
        allow: Path | None = None,
        insecure: bool = False,
    ) -> Security:
        """Load the key files (named errors for bad ones) and check the combination."""
        if (server_key is not None or allow is not None) and secret is None:
            raise KeyFileError("--server-key/--allow need --curve-secret (our own key pair)")
        pair = load_secret(secret) if secret is not None else None
        server = read_key_file(server_key, secret=False).public if server_key else None
        if allow is not None and not allow.is_dir():
            raise KeyFileError(f"{allow}: --allow expects a folder of public .key files")
        return cls(pair, server, allow, insecure)


def load_secret(path: Path) -> KeyPair:
    """Read a ``.key_secret`` file and check that its public key is its secret key's."""
    pair = read_key_file(path, secret=True)
    if pair.secret is None:  # read_key_file(secret=True) already refuses this
        raise KeyFileError(f"{path}: no secret-key line")
    try:
        derived = zmq.curve_public(pair.secret)
    except zmq.ZMQError as exc:
        raise KeyFileError(f"{path}: secret-key is not a valid CURVE key ({exc})") from None
    if derived != pair.public:
        raise KeyFileError(f"{path}: public-key does not belong to secret-key")
    return pair


def is_loopback(endpoint: str) -> bool:
    """True for ipc/inproc endpoints and TCP on 127.0.0.0/8, ``localhost`` or ``::1``."""
    if not endpoint.startswith("tcp://"):
        return True
    host = endpoint[len("tcp://") :].rsplit(":", 1)[0]
    if host in _LOOPBACK_HOSTS:
        return True
    parts = host.split(".")
    return len(parts) == 4 and parts[0] == "127" and all(p.isdigit() for p in parts)


def curve_server(sock: zmq.Socket[bytes], secret: KeyPair) -> None:
    """Make ``sock`` a CURVE server with our key pair (before it binds)."""
    if secret.secret is None:
        raise KeyFileError("a CURVE server needs a secret key (the .key_secret file)")
    sock.setsockopt(zmq.CURVE_SECRETKEY, secret.secret)
    sock.setsockopt(zmq.CURVE_PUBLICKEY, secret.public)
    sock.setsockopt(zmq.CURVE_SERVER, 1)


def curve_client(sock: zmq.Socket[bytes], secret: KeyPair, server_public: bytes) -> None:
    """Make ``sock`` a CURVE client of the server whose public key is given (before connect)."""
    if secret.secret is None:
        raise KeyFileError("a CURVE client needs a secret key (the .key_secret file)")
    sock.setsockopt(zmq.CURVE_SECRETKEY, secret.secret)
    sock.setsockopt(zmq.CURVE_PUBLICKEY, secret.public)
    sock.setsockopt(zmq.CURVE_SERVERKEY, server_public)


def start_authenticator(ctx: zmq.Context[zmq.Socket[bytes]], allow: Path) -> ThreadAuthenticator:
    """Run pyzmq's ZAP authenticator in ``ctx``, letting in the CURVE keys found in ``allow``.

    Refusals are logged (debug) on the ``livedrummer.auth`` logger. Call ``stop()`` on the
    result before terminating the context.
    """
    auth = ThreadAuthenticator(ctx, log=logging.getLogger("livedrummer.auth"))
    auth.start()
    auth.configure_curve(domain="*", location=str(allow))
    return auth


def bind(
    sock: zmq.Socket[bytes], endpoint: str, what: str, security: Security | None = None
) -> str:
    """Bind and return the real endpoint (the OS-chosen port for ``tcp://HOST:*``).

    With ``security.secret`` the socket becomes a CURVE server first. A non-loopback TCP
    address without CURVE is refused unless ``security.insecure``.
    """
    check_endpoint(endpoint, what)
    security = security or Security()
    if security.secret is not None:
        curve_server(sock, security.secret)
    elif not security.insecure and not is_loopback(endpoint):
        raise ProtocolError(
            f"{what}: refusing to bind {endpoint} without CURVE "
            "(give --curve-secret FILE, or --insecure to allow plain remote access)"
        )
    try:
        sock.bind(endpoint)
    except zmq.ZMQError as exc:
        raise ProtocolError(f"{what}: cannot bind {endpoint}: {exc}") from exc
    last = sock.getsockopt(zmq.LAST_ENDPOINT)
    return last.decode() if isinstance(last, bytes) else str(last)


def connect(
    sock: zmq.Socket[bytes], endpoint: str, what: str, security: Security | None = None
) -> None:
    """Connect; as a CURVE client when ``security`` has the server's key (and so our pair).

    Without ``server_public`` the connection is plain even if we have a key pair (a synth
    may serve its poses with CURVE while reading a local input daemon in the clear).
    """
    check_endpoint(endpoint, what)
    if security is not None and security.server_public is not None:
        if security.secret is None:
            raise KeyFileError(f"{what}: --server-key needs --curve-secret (our key pair)")
        curve_client(sock, security.secret, security.server_public)
    try:
        sock.connect(endpoint)
    except zmq.ZMQError as exc:
        raise ProtocolError(f"{what}: cannot connect to {endpoint}: {exc}") from exc


def request_ready(
    ctx: zmq.Context[zmq.Socket[bytes]],
    endpoint: str,
    hello: Hello,
    timeout_s: float,
    security: Security | None = None,
) -> Hello:
    """Send HELLO to a service's control socket and wait (bounded) for its READY."""
    sock = socket(ctx, zmq.DEALER)
    try:
        connect(sock, endpoint, "control endpoint", security)
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


def subscribe_protocol(sock: zmq.Socket[bytes]) -> None:
    """Subscribe a SUB socket to every livedrummer message: any kind, any version.

    Wider than one :func:`~livedrummer.protocol.topic` per kind on purpose: a message of
    another protocol version (or a malformed one that starts with the magic) then reaches
    :func:`~livedrummer.protocol.decode` and is counted and logged by the receiver, instead of
    being filtered out unseen, which would look like silence. Counts as one subscription for
    the input daemon's ``wait_subscribers``.
    """
    sock.setsockopt(zmq.SUBSCRIBE, MAGIC)


def serve_control(
    sock: Any,
    stop: threading.Event,
    ready: Callable[[], Message],
    bad: BadMessages,
    on_drop: Callable[[str], None] | None = None,
) -> None:
    """Answer HELLO with ``ready()`` on a ROUTER socket until ``stop``; then close the socket.

    Anything else (undecodable frames, or a valid message other than HELLO) is dropped,
    counted in ``bad`` (logged once per kind) and reported to ``on_drop`` with its kind; the
    loop keeps serving. Replies keep the client's envelope (a DEALER's empty delimiter too).
    """
    try:
        while not stop.is_set():
            if not sock.poll(100):
                continue
            frames = sock.recv_multipart()
            ident, rest = frames[0], frames[1:]
            envelope = [ident]
            if rest and rest[0] == b"":
                envelope.append(b"")
                rest = rest[1:]
            try:
                msg = decode(rest)
            except ProtocolError as exc:
                kind = bad.drop(exc)
                if on_drop is not None:
                    on_drop(kind)
                continue
            if msg.kind is not Kind.HELLO:
                bad.unexpected(msg.kind.name)
                if on_drop is not None:
                    on_drop("unexpected")
                continue
            sock.send_multipart([*envelope, *encode(ready())])
    finally:
        sock.close(0)
