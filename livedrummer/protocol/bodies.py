"""Message bodies: HELLO/READY (:class:`Hello`), POSE, GAP, and the :class:`Message` itself.

Plain frozen dataclasses; :class:`Hello` is the one JSON payload and checks it key by key
when read (:meth:`Hello.from_bytes`), everything else is record arrays or fixed structs.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from livedrummer.errors import ProtocolError
from livedrummer.protocol.poseformat import PoseFormat
from livedrummer.protocol.spec import (
    AVATAR_DIGEST_LEN,
    HELLO_KEYS,
    MAX_HELLO,
    PROTOCOL_VERSION,
    U16,
    GapReason,
    Kind,
    Stream,
    fail,
)


@dataclass(frozen=True)
class Hello:
    """HELLO/READY body: who is speaking and where its sockets are."""

    service: str
    role: str
    performer: int = 0
    endpoints: Mapping[str, str] = field(default_factory=dict)
    pose: PoseFormat | None = None
    protocol: int = PROTOCOL_VERSION
    avatar: str = ""  # the avatar's digest; "" for the built-in character

    def to_bytes(self) -> bytes:
        obj = {
            "service": self.service,
            "role": self.role,
            "protocol": self.protocol,
            "performer": self.performer,
            "endpoints": dict(self.endpoints),
            "pose": None if self.pose is None else self.pose.to_json(),
            "avatar": self.avatar,
        }
        return json.dumps(obj, separators=(",", ":"), sort_keys=True).encode()

    @classmethod
    def from_bytes(cls, data: bytes) -> Hello:
        if len(data) > MAX_HELLO:
            raise fail("hello", f"longer than {MAX_HELLO} bytes", len(data))
        try:
            obj = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            raise fail("hello", f"not UTF-8 JSON ({exc.__class__.__name__})", data[:40]) from exc
        required = {k for k, (needed, _) in HELLO_KEYS.items() if needed}
        if not isinstance(obj, dict) or not required <= set(obj) <= set(HELLO_KEYS):
            got = sorted(obj) if isinstance(obj, dict) else obj
            raise fail("hello", f"expected keys {sorted(HELLO_KEYS)}", got)
        for key in ("service", "role"):
            if not isinstance(obj[key], str) or not 0 < len(obj[key]) <= 200:
                raise fail(f"hello.{key}", "expected a short string", obj[key])
        if obj["protocol"] != PROTOCOL_VERSION or type(obj["protocol"]) is not int:
            raise fail("hello.protocol", f"expected {PROTOCOL_VERSION}", obj["protocol"])
        performer = obj["performer"]
        if type(performer) is not int or not 0 <= performer <= U16:
            raise fail("hello.performer", "expected an integer 0..65535", performer)
        endpoints = obj["endpoints"]
        if not isinstance(endpoints, dict) or not all(
            isinstance(v, str) and len(v) < 1024 for v in endpoints.values()
        ):
            raise fail("hello.endpoints", "expected {name: endpoint string}", endpoints)
        pose = None if obj["pose"] is None else PoseFormat.from_json(obj["pose"])
        avatar = obj.get("avatar", "")
        if not isinstance(avatar, str) or (
            avatar and (len(avatar) != AVATAR_DIGEST_LEN or avatar.strip("0123456789abcdef"))
        ):
            raise fail("hello.avatar", f"expected {AVATAR_DIGEST_LEN} hex digits or ''", avatar)
        return cls(obj["service"], obj["role"], performer, dict(endpoints), pose, avatar=avatar)


@dataclass(frozen=True)
class Pose:
    """POSE body: rows of the announced pose dtype, valid at ``time_s`` on the shared clock."""

    time_s: float
    rows: np.ndarray


@dataclass(frozen=True)
class Gap:
    """GAP body: the sender knows it lost ``dropped`` events between the two times."""

    dropped: int
    first_time_s: float
    last_time_s: float
    reason: GapReason


Body = Hello | np.ndarray | Pose | Gap | None


@dataclass(frozen=True)
class Message:
    """One decoded (or to-be-encoded) message: header fields and a body of the kind's type."""

    kind: Kind
    body: Body = None
    performer: int = 0
    seq: int = 0
    send_time_s: float = 0.0
    stream: int = Stream.EVENTS
    flags: int = 0

    @property
    def rows(self) -> np.ndarray:
        """ONSET/CONTROL rows."""
        if not isinstance(self.body, np.ndarray):
            raise ProtocolError(f"{self.kind.name} message has no rows")
        return self.body
