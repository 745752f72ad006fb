"""Does a live display draw the avatar the synth plays? One question at start-up, one line.

The synth's rig has its avatar's proportions (its stick tips land on the drums for *that*
body) and it announces the avatar's digest in READY (:data:`livedrummer.protocol.HELLO_KEYS`,
``avatar``; empty for the built-in character). A display started with another avatar would
draw limbs of other lengths on those joint positions: the show goes on, but the display says
so once, as a warning naming both. Asked over the synth's control socket with a bounded wait,
so a synth that does not answer only costs that wait and a line saying its avatar is unknown.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from livedrummer.errors import ProtocolError
from livedrummer.protocol import Hello

if TYPE_CHECKING:
    import zmq

    from livedrummer.avatar.model import Avatar

    from ..wire.net import Security

log = logging.getLogger("livedrummer.display")


def describe(digest: str, avatar: Avatar | None = None) -> str:
    if not digest:
        return "the built-in character"
    name = f"{avatar.name} " if avatar is not None else ""
    return f"avatar {name}({digest})"


def avatar_mismatch(ours: Avatar | None, theirs: str) -> str | None:
    """The one-line warning when the synth's avatar digest ``theirs`` is not ours, else None."""
    mine = "" if ours is None else ours.digest
    if mine == theirs:
        return None
    return (
        f"display: this display draws {describe(mine, ours)} but the synth plays "
        f"{describe(theirs)}: limbs are drawn with other proportions than they are played "
        "with (give both the same --avatar)"
    )


def check_synth_avatar(
    ctx: zmq.Context[zmq.Socket[bytes]],
    endpoint: str,
    avatar: Avatar | None,
    security: Security | None = None,
    timeout_s: float = 5.0,
) -> str | None:
    """Ask the synth at ``endpoint`` for READY and warn (log and return the line) when its
    avatar is not ``avatar``; None when they agree."""
    from ..wire.net import request_ready

    hello = Hello("display", "frames", avatar="" if avatar is None else avatar.digest)
    try:
        ready = request_ready(ctx, endpoint, hello, timeout_s, security)
    except ProtocolError as exc:
        unknown = f"display: the synth's avatar is not known ({exc})"
        log.warning("%s", unknown)
        return unknown
    line = avatar_mismatch(avatar, ready.avatar)
    if line is not None:
        log.warning("%s", line)
    return line
