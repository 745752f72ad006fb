"""The wire's one table: constants, kinds, flags, streams, and :data:`SPECS`.

Everything :mod:`~livedrummer.protocol.codec` encodes or decodes is described here once: the
header layout (:data:`HEADER`), the kinds and their payload layouts (:data:`SPECS`), the
limits a receiver checks. :class:`WireError` is the one error about bytes on the wire; the
``field`` it names lets a receiver count its drops by kind. See the package docstring for
the documented schema, which this table *is*.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum, IntFlag
from typing import Any

import numpy as np

from livedrummer.errors import ProtocolError
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, STAGE_CUE_DTYPE

# 2: SHOWN_ONSET. SHOWN_CONTROL (9) and STAGE_CUE (10) came later without a bump: a version-2
# peer that lacks them refuses them as unknown kinds (counted and dropped), never misreads one.
PROTOCOL_VERSION = 2
MAGIC = b"LDRM"
HEADER = struct.Struct("<4sBBHHHQdI")
POSE_HEADER = struct.Struct("<8sI4xd")
GAP_PAYLOAD = struct.Struct("<QddI")
MAX_PAYLOAD = 16 * 1024 * 1024
MAX_ROWS = 1 << 20
MAX_HELLO = 64 * 1024
MAX_POSE_ITEMSIZE = 1 << 20
U16 = 0xFFFF
U64 = (1 << 64) - 1


class Kind(IntEnum):
    HELLO = 1
    READY = 2
    ONSET = 3
    CONTROL = 4
    POSE = 5
    HEARTBEAT = 6
    GAP = 7
    SHOWN_ONSET = 8  # an onset forwarded to displays, stamped with its show time
    SHOWN_CONTROL = 9  # a control (choke, hi-hat pedal) forwarded likewise
    STAGE_CUE = 10  # a cue's camera and blackout, sent to displays stamped with its show time


class Flag(IntFlag):
    """Header flag bits."""

    SIMULATED = 1  # played from a file as if performed (demo, tests)
    RELAYED = 2  # received from a remote site and republished here


KNOWN_FLAGS = int(Flag.SIMULATED | Flag.RELAYED)


class Stream(IntEnum):
    """Conventional stream ids (a sender may use others)."""

    EVENTS = 0  # onsets, controls, heartbeats and gaps of one input daemon
    POSES = 1  # poses of one synth, the onsets and controls it forwards, its stage cues
    CONTROL = 2  # hello/ready on a control socket (sequence numbers unused there)


class GapReason(IntEnum):
    QUEUE_FULL = 1  # the sender shed events under load
    SOURCE_LOST = 2  # the device disappeared; events may have been played meanwhile
    UPSTREAM = 3  # a relayed stream had a gap before it reached us


@dataclass(frozen=True, slots=True)
class KindSpec:
    """One row of the schema table."""

    kind: Kind
    frames: int  # payload frames after the header
    layout: str  # "json", "rows", "pose", "empty", "struct"
    rows: np.dtype[Any] | None = None
    fixed: struct.Struct | None = None


SPECS: dict[int, KindSpec] = {
    s.kind: s
    for s in (
        KindSpec(Kind.HELLO, 1, "json"),
        KindSpec(Kind.READY, 1, "json"),
        KindSpec(Kind.ONSET, 1, "rows", rows=ONSET_DTYPE),
        KindSpec(Kind.CONTROL, 1, "rows", rows=CONTROL_DTYPE),
        KindSpec(Kind.POSE, 2, "pose", fixed=POSE_HEADER),
        KindSpec(Kind.HEARTBEAT, 1, "empty"),
        KindSpec(Kind.GAP, 1, "struct", fixed=GAP_PAYLOAD),
        KindSpec(Kind.SHOWN_ONSET, 1, "rows", rows=ONSET_DTYPE),
        KindSpec(Kind.SHOWN_CONTROL, 1, "rows", rows=CONTROL_DTYPE),
        KindSpec(Kind.STAGE_CUE, 1, "rows", rows=STAGE_CUE_DTYPE),
    )
}


#: The HELLO/READY JSON object's keys, in the one place they are listed: key -> (required, what
#: it holds). :class:`~livedrummer.protocol.bodies.Hello` writes every key and reads exactly these
#: (a key that is not required may be absent: a peer from before it was added).
HELLO_KEYS: dict[str, tuple[bool, str]] = {
    "service": (True, "the speaker's service name (input, synth, display)"),
    "role": (True, "what it sends: source, poses, frames, or a client's own word"),
    "protocol": (True, "PROTOCOL_VERSION"),
    "performer": (True, "performer id 0..65535"),
    "endpoints": (True, "{name: zmq endpoint} of its sockets"),
    "pose": (True, "PoseFormat JSON of the POSE rows it sends, or null"),
    "avatar": (
        False,
        "digest (16 hex digits) of the avatar whose proportions it plays or "
        "draws; empty for the built-in character",
    ),
}
AVATAR_DIGEST_LEN = 16


def topic(kind: Kind) -> bytes:
    """Prefix to subscribe to one kind of message on a SUB socket."""
    return MAGIC + bytes((PROTOCOL_VERSION, int(kind)))


class WireError(ProtocolError):
    """A :class:`ProtocolError` about bytes on the wire, with the field it names in ``field``."""

    def __init__(self, message: str, field_name: str) -> None:
        super().__init__(message)
        self.field = field_name


def fail(name: str, problem: str, value: object, field_name: str | None = None) -> WireError:
    text = repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    return WireError(f"{name}: {problem} (got {text})", field_name or name)
