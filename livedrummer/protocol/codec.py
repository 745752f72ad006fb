"""Encode and decode: a :class:`~livedrummer.protocol.bodies.Message` to frames and back.

Both read :data:`~livedrummer.protocol.spec.SPECS`, so the table drives the format. Decoded
arrays are zero-copy, read-only views of the received frames; any violation raises a
:class:`~livedrummer.protocol.spec.WireError` naming the field and the value, and nothing
else is raised on bad bytes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from livedrummer.errors import ProtocolError
from livedrummer.protocol.bodies import Body, Gap, Hello, Message, Pose
from livedrummer.protocol.poseformat import PoseFormat
from livedrummer.protocol.rows import ROW_CHECKS, rows_from
from livedrummer.protocol.spec import (
    GAP_PAYLOAD,
    HEADER,
    KNOWN_FLAGS,
    MAGIC,
    MAX_PAYLOAD,
    MAX_ROWS,
    POSE_HEADER,
    PROTOCOL_VERSION,
    SPECS,
    U16,
    U64,
    GapReason,
    Kind,
    WireError,
    fail,
)


def encode(msg: Message, pose_format: PoseFormat | None = None) -> list[bytes]:
    """Frames for ``msg``; raises :class:`ProtocolError` if the message is not valid."""
    spec = SPECS.get(int(msg.kind))
    if spec is None:
        raise fail("kind", "unknown", msg.kind)
    payload: list[bytes]
    body = msg.body
    if spec.layout == "json":
        if not isinstance(body, Hello):
            raise fail("body", f"{spec.kind.name} needs a Hello", type(body).__name__)
        payload = [body.to_bytes()]
    elif spec.layout == "rows":
        assert spec.rows is not None
        if not isinstance(body, np.ndarray) or body.dtype != spec.rows or body.ndim != 1:
            got = body.dtype if isinstance(body, np.ndarray) else type(body).__name__
            raise fail("body", f"{spec.kind.name} needs a 1-d {spec.rows} array", got)
        if not 0 < body.size <= MAX_ROWS:
            raise fail("body", f"expected 1..{MAX_ROWS} rows", body.size)
        ROW_CHECKS[spec.kind](body)
        payload = [np.ascontiguousarray(body).tobytes()]
    elif spec.layout == "pose":
        if pose_format is None:
            raise ProtocolError("pose: no pose format given to encode")
        if not isinstance(body, Pose) or body.rows.dtype != pose_format.dtype:
            raise fail("body", "POSE needs a Pose of the announced dtype", type(body).__name__)
        n = body.rows.size
        if body.rows.ndim != 1 or not 0 < n <= MAX_ROWS or not math.isfinite(body.time_s):
            raise fail("pose", "expected 1-d rows and a finite time", (n, body.time_s))
        head = POSE_HEADER.pack(pose_format.hash, n, body.time_s)
        payload = [head, np.ascontiguousarray(body.rows).tobytes()]
    elif spec.layout == "struct":
        if not isinstance(body, Gap):
            raise fail("body", "GAP needs a Gap", type(body).__name__)
        if not 0 <= body.dropped <= U64 or body.reason not in set(GapReason):
            raise fail("gap", "dropped or reason out of range", (body.dropped, body.reason))
        payload = [GAP_PAYLOAD.pack(body.dropped, body.first_time_s, body.last_time_s, body.reason)]
    else:
        if body is not None:
            raise fail("body", "HEARTBEAT has no body", type(body).__name__)
        payload = [b""]
    total = sum(len(p) for p in payload)
    if total > MAX_PAYLOAD:
        raise fail("payload_len", f"larger than {MAX_PAYLOAD}", total)
    _check_header_values(msg.flags, msg.performer, msg.stream, msg.seq, msg.send_time_s)
    head = HEADER.pack(
        MAGIC,
        PROTOCOL_VERSION,
        int(spec.kind),
        msg.flags,
        msg.performer,
        msg.stream,
        msg.seq,
        msg.send_time_s,
        total,
    )
    return [head, *payload]


def _check_header_values(flags: int, performer: int, stream: int, seq: int, t: float) -> None:
    if flags & ~KNOWN_FLAGS or not 0 <= flags <= U16:
        raise fail("flags", f"unknown bits (known mask {KNOWN_FLAGS:#x})", flags)
    if not 0 <= performer <= U16:
        raise fail("performer", "out of range 0..65535", performer)
    if not 0 <= stream <= U16:
        raise fail("stream", "out of range 0..65535", stream)
    if not 0 <= seq <= U64:
        raise fail("seq", "out of range for u64", seq)
    if not math.isfinite(t):
        raise fail("send_time_s", "not finite", t)


def _view(frame: object, index: int) -> memoryview:
    try:
        view = memoryview(frame)  # type: ignore[arg-type]
    except TypeError as exc:
        raise fail(f"frame {index}", "not a bytes-like object", type(frame).__name__) from exc
    if view.ndim != 1 or view.itemsize != 1:
        view = view.cast("B")
    return view


def decode(
    frames: Sequence[object],
    pose_format: PoseFormat | None = None,
    max_payload: int = MAX_PAYLOAD,
) -> Message:
    """Validate and decode ``frames`` (as from ``recv_multipart``); see the module docstring."""
    if not frames:
        raise fail("frames", "no frames", 0)
    head = _view(frames[0], 0)
    if len(head) != HEADER.size:
        raise fail("header", f"expected {HEADER.size} bytes", len(head))
    magic, version, kind, flags, performer, stream, seq, t, length = HEADER.unpack(head)
    if magic != MAGIC:
        raise fail("magic", f"expected {MAGIC!r}", magic)
    if version != PROTOCOL_VERSION:
        raise fail("version", f"expected {PROTOCOL_VERSION}", version)
    spec = SPECS.get(kind)
    if spec is None:
        raise fail("kind", f"unknown (known {sorted(SPECS)})", kind)
    _check_header_values(flags, performer, stream, seq, t)
    if length > max_payload:
        raise fail("payload_len", f"larger than {max_payload}", length, "max_payload")
    if len(frames) != 1 + spec.frames:
        raise fail("frames", f"{spec.kind.name} needs {1 + spec.frames} frames", len(frames))
    parts = [_view(f, i) for i, f in enumerate(frames[1:], start=1)]
    total = sum(len(p) for p in parts)
    if total != length:
        raise fail("payload_len", f"header says {length}, frames hold {total}", length)
    body: Body
    if spec.layout == "json":
        body = Hello.from_bytes(parts[0].tobytes())
    elif spec.layout == "rows":
        assert spec.rows is not None
        body = rows_from(parts[0], spec.rows, spec.kind.name)
        ROW_CHECKS[spec.kind](body)
    elif spec.layout == "pose":
        body = _decode_pose(parts, pose_format)
    elif spec.layout == "struct":
        if len(parts[0]) != GAP_PAYLOAD.size:
            raise fail("gap payload", f"expected {GAP_PAYLOAD.size} bytes", len(parts[0]))
        dropped, first, last, reason = GAP_PAYLOAD.unpack(parts[0])
        if reason not in GapReason._value2member_map_:
            raise fail("gap.reason", "unknown", reason)
        if not (math.isfinite(first) and math.isfinite(last)):
            raise fail("gap times", "not finite", (first, last))
        body = Gap(dropped, first, last, GapReason(reason))
    else:
        if len(parts[0]):
            raise fail("heartbeat payload", "expected 0 bytes", len(parts[0]))
        body = None
    return Message(Kind(kind), body, performer, seq, t, stream, flags)


def _decode_pose(parts: list[memoryview], fmt: PoseFormat | None) -> Pose:
    if fmt is None:
        raise WireError("pose: no pose format was announced to this receiver (got a POSE)", "pose")
    if len(parts[0]) != POSE_HEADER.size:
        raise fail("pose header", f"expected {POSE_HEADER.size} bytes", len(parts[0]))
    digest, n, time_s = POSE_HEADER.unpack(parts[0])
    if digest != fmt.hash:
        raise fail("pose.hash", f"expected {fmt.hash.hex()}", digest.hex())
    if not math.isfinite(time_s):
        raise fail("pose.time_s", "not finite", time_s)
    rows = rows_from(parts[1], fmt.dtype, "POSE")
    if rows.size != n:
        raise fail("pose.rows", f"header says {n}, payload holds {rows.size}", n)
    return Pose(time_s, rows)
