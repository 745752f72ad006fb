"""A free block of loopback ports for a rig of services started by a bench or a test.

`up --port-base N` binds N, N+1, ... for its services' endpoints. A base drawn at random from a
range that overlaps the kernel's ephemeral ports (32768-60999 on Linux) can collide with the
source port of any outgoing connection on the machine, a ZeroMQ connect of this very rig
included: the synth then fails with "Address already in use" once in a few hundred runs. The
block is therefore drawn below the ephemeral range and each of its ports is bound once before
it is handed out. A port can still be taken between that probe and the service's bind; the
window is milliseconds and the range holds no ephemeral ports, so that is left to chance.
"""

from __future__ import annotations

import random
import socket
from pathlib import Path

LOW = 20_000
BLOCK = 20


def _ephemeral_low() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 32_768


def _bindable(port: int) -> bool:
    for kind in (socket.SOCK_STREAM, socket.SOCK_DGRAM):
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                return False
    return True


def free_port_base(count: int = BLOCK, tries: int = 200) -> int:
    """The first port of `count` consecutive loopback ports, all free now, none ephemeral."""
    high = max(LOW + count, min(_ephemeral_low(), 65_536) - count)
    rng = random.Random()
    for _ in range(tries):
        base = rng.randrange(LOW, high, BLOCK) if high - LOW > BLOCK else LOW
        if all(_bindable(base + i) for i in range(count)):
            return base
    raise OSError(f"no block of {count} free loopback ports between {LOW} and {high}")


def free_port() -> int:
    """One free loopback port outside the ephemeral range."""
    return free_port_base(1)
