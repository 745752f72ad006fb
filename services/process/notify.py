"""Readiness notification: how a service tells whoever started it "I am serving now".

A launcher must not guess with sleeps when a process is ready. A service calls :func:`ready`
once its sockets are bound and its first state is built. Two receivers are supported at once:

* the livedrummer launcher passes a pipe's write end in ``LIVEDRUMMER_NOTIFY_FD``; the
  service writes one line ``READY <detail>`` to it;
* systemd (``Type=notify`` units in ``deploy/``) passes ``NOTIFY_SOCKET``; the service sends
  ``READY=1`` there, as ``sd_notify(3)`` does, without needing libsystemd.

With neither set (a service started by hand) :func:`ready` does nothing.
"""

from __future__ import annotations

import logging
import os
import socket

log = logging.getLogger(__name__)

NOTIFY_FD_ENV = "LIVEDRUMMER_NOTIFY_FD"


def ready(detail: str = "") -> None:
    """Announce readiness to the launcher and/or systemd (each at most once per process)."""
    fd_text = os.environ.pop(NOTIFY_FD_ENV, None)
    if fd_text:
        try:
            fd = int(fd_text)
            os.write(fd, f"READY {detail}".rstrip().encode() + b"\n")
            os.close(fd)
        except (ValueError, OSError) as exc:
            log.warning("could not notify the launcher on fd %r: %s", fd_text, exc)
    address = os.environ.pop("NOTIFY_SOCKET", None)
    if address:
        if address.startswith("@"):  # abstract namespace socket
            address = "\0" + address[1:]
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as sock:
                sock.sendto(b"READY=1\nSTATUS=" + detail.encode() + b"\n", address)
        except OSError as exc:
            log.warning("could not notify systemd at %r: %s", address, exc)
