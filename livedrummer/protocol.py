"""The livedrummer wire format: versioned multipart ZeroMQ messages, one table drives it all.

Why this shape. Onsets, controls and poses are already fixed-dtype numpy record arrays inside
the library, so the cheapest safe wire format is *those bytes*: a small fixed-layout header
frame followed by raw payload frame(s). Nothing that crosses a socket is unpickled or
evaluated; the one JSON payload (HELLO/READY, sent once per connection) is parsed with
``json.loads`` and checked key by key. :data:`SPECS` is the single table of message kinds:
:func:`encode` and :func:`decode` both read it, so the documented schema below *is* the code.

Header frame (:data:`HEADER`, little-endian, 32 bytes)::

    offset size field         type  meaning
    0      4    magic         4s    b"LDRM"
    4      1    version       u8    PROTOCOL_VERSION (1); any other value is refused
    5      1    kind          u8    Kind (table below)
    6      2    flags         u16   Flag bits; unknown bits are refused
    8      2    performer     u16   who played it (same space as the onset ``source`` field)
    10     2    stream        u16   sender's stream id (Stream); sequence numbers count per
                                    (performer, stream)
    12     8    seq           u64   sequence number, +1 for *every* message on the stream
                                    (heartbeats and gaps included), 0 after a sender restart
    20     8    send_time_s   f64   send time on the machine's shared clock (livedrummer.clock)
    28     4    payload_len   u32   total bytes of the payload frames (checked)

Because the header starts with magic, version and kind, a SUB socket can filter one kind with
:func:`topic` (e.g. onsets only) without a separate topic frame.

Kinds (:data:`SPECS`; "frames" counts the payload frames after the header)::

    kind       code frames payload
    HELLO      1    1      UTF-8 JSON object (Hello): service, role, protocol, performer,
                           endpoints {name: zmq endpoint}, pose (PoseFormat JSON or null)
    READY      2    1      same JSON as HELLO: the service's answer, sent once it is serving
    ONSET      3    1      n >= 1 rows of events.ONSET_DTYPE (20 bytes each), time order
    CONTROL    4    1      n >= 1 rows of events.CONTROL_DTYPE (14 bytes each), time order
    POSE       5    2      POSE_HEADER (hash 8s, rows u32, pad 4, time_s f64; 24 bytes)
                           + n >= 1 rows of the pose dtype announced in HELLO/READY
    HEARTBEAT  6    1      empty (0 bytes): the sender is alive; lets a tail gap show
    GAP        7    1      GAP_PAYLOAD (dropped u64, first_time_s f64, last_time_s f64,
                           reason u32; 28 bytes): the *sender* shed or lost events

Limits checked by :func:`decode`: header size exact; payload_len <= ``max_payload``
(default :data:`MAX_PAYLOAD`, 16 MiB) and equal to the frames' total; row payloads a whole
number of rows, 1 … :data:`MAX_ROWS`; every onset/control field in range (codes index the
vocabulary, MIDI values < 128, channels < 16, times finite); POSE rows match the announced
dtype's hash and size; HELLO JSON <= 64 KiB with exactly the known keys. Any violation raises
:class:`~livedrummer.errors.ProtocolError` naming the field and the value, and nothing else is
ever raised on bad bytes (a hypothesis fuzz test holds us to it). Errors about the wire are
:class:`WireError`, whose ``field`` attribute names that field for a program (``"version"``,
``"payload_len"``, ``"row 3.note"``; ``"max_payload"`` for the size limit), so a receiver can
count its drops by kind without parsing the message.

The pose dtype belongs to the body engine and is opaque here: :class:`PoseFormat` turns any
structured dtype (scalar or nested fields, subarrays, padding; no Python objects) into a
canonical JSON description and an 8-byte BLAKE2b hash. The synth announces it in READY, and
each POSE header repeats the hash so a display built against another dtype refuses the frame.

Decoded arrays are zero-copy, read-only views of the received frames. Limits: no
compression, no fragmentation (one message <= ``max_payload``), integrity is ZeroMQ's (TCP),
and authentication/encryption are a socket option (CURVE), not part of this format.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import IntEnum, IntFlag
from typing import Any

import numpy as np

from livedrummer.errors import ProtocolError
from livedrummer.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind
from livedrummer.vocabulary import HIHATS, INSTRUMENTS, ZONES

PROTOCOL_VERSION = 1
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


class Flag(IntFlag):
    """Header flag bits."""

    SIMULATED = 1  # played from a file as if performed (demo, tests)
    RELAYED = 2  # received from a remote site and republished here


KNOWN_FLAGS = int(Flag.SIMULATED | Flag.RELAYED)


class Stream(IntEnum):
    """Conventional stream ids (a sender may use others)."""

    EVENTS = 0  # onsets, controls, heartbeats and gaps of one input daemon
    POSES = 1  # poses of one synth
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
    )
}


def topic(kind: Kind) -> bytes:
    """Prefix to subscribe to one kind of message on a SUB socket."""
    return MAGIC + bytes((PROTOCOL_VERSION, int(kind)))


class WireError(ProtocolError):
    """A :class:`ProtocolError` about bytes on the wire, with the field it names in ``field``."""

    def __init__(self, message: str, field_name: str) -> None:
        super().__init__(message)
        self.field = field_name


def _fail(name: str, problem: str, value: object, field_name: str | None = None) -> WireError:
    text = repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    return WireError(f"{name}: {problem} (got {text})", field_name or name)


# --------------------------------------------------------------------------------------------
# Pose format: any structured dtype, described canonically and hashed
# --------------------------------------------------------------------------------------------

_SCALAR = re.compile(r"^[<>|][biufcV?]\d{1,6}$")


def _describe(dtype: np.dtype[Any]) -> dict[str, Any]:
    if dtype.fields is None or dtype.names is None:
        raise ProtocolError(f"pose dtype: must be a structured dtype (got {dtype})")
    formats = []
    offsets = []
    for name in dtype.names:
        sub, offset = dtype.fields[name][:2]
        shape = list(sub.shape)
        base = sub.base
        if base.fields is not None:
            formats.append({"struct": _describe(base), "shape": shape})
        else:
            if base.hasobject or not _SCALAR.match(base.str):
                raise ProtocolError(f"pose dtype: field {name!r}: unsupported type {base.str}")
            formats.append({"type": base.str, "shape": shape})
        offsets.append(int(offset))
    return {
        "names": list(dtype.names),
        "formats": formats,
        "offsets": offsets,
        "itemsize": int(dtype.itemsize),
    }


def _build(desc: object, where: str, depth: int = 0) -> np.dtype[Any]:
    if depth > 8:
        raise _fail(where, "nested too deep", depth)
    if not isinstance(desc, dict) or set(desc) != {"names", "formats", "offsets", "itemsize"}:
        raise _fail(where, "expected {names, formats, offsets, itemsize}", desc)
    names, formats, offsets, itemsize = (
        desc["names"],
        desc["formats"],
        desc["offsets"],
        desc["itemsize"],
    )
    if not (isinstance(names, list) and isinstance(formats, list) and isinstance(offsets, list)):
        raise _fail(where, "names, formats, offsets must be lists", desc)
    if not names or not len(names) == len(formats) == len(offsets) or len(names) > 4096:
        raise _fail(where, "names, formats and offsets differ in length or are empty", desc)
    if not all(isinstance(n, str) and n for n in names) or len(set(names)) != len(names):
        raise _fail(f"{where}.names", "expected distinct non-empty strings", names)
    if not all(type(o) is int and 0 <= o <= MAX_POSE_ITEMSIZE for o in offsets):
        raise _fail(f"{where}.offsets", "expected integers in range", offsets)
    if type(itemsize) is not int or not 0 < itemsize <= MAX_POSE_ITEMSIZE:
        raise _fail(f"{where}.itemsize", f"expected 1..{MAX_POSE_ITEMSIZE}", itemsize)
    built: list[Any] = []
    for name, fmt in zip(names, formats, strict=True):
        place = f"{where}.{name}"
        if not isinstance(fmt, dict) or set(fmt) not in ({"type", "shape"}, {"struct", "shape"}):
            raise _fail(place, "expected {type|struct, shape}", fmt)
        shape = fmt["shape"]
        if (
            not isinstance(shape, list)
            or len(shape) > 8
            or not all(type(n) is int and 0 < n <= MAX_POSE_ITEMSIZE for n in shape)
        ):
            raise _fail(f"{place}.shape", "expected a list of positive integers", shape)
        if "type" in fmt:
            typestr = fmt["type"]
            if not isinstance(typestr, str) or not _SCALAR.match(typestr):
                raise _fail(f"{place}.type", "unsupported scalar type", typestr)
            try:
                base = np.dtype(typestr)
            except TypeError as exc:
                raise _fail(f"{place}.type", "not a numpy type", typestr) from exc
        else:
            base = _build(fmt["struct"], place, depth + 1)
        if math.prod(shape) * base.itemsize > MAX_POSE_ITEMSIZE:
            raise _fail(place, "field too large", shape)
        built.append((base, tuple(shape)) if shape else base)
    try:
        return np.dtype(
            {"names": names, "formats": built, "offsets": offsets, "itemsize": itemsize}
        )
    except (TypeError, ValueError) as exc:
        raise _fail(where, f"inconsistent layout ({exc})", desc) from exc


def _canonical(desc: Mapping[str, Any]) -> str:
    return json.dumps(desc, separators=(",", ":"), sort_keys=True)


@dataclass(frozen=True)
class PoseFormat:
    """A pose dtype with its canonical description and 8-byte hash."""

    dtype: np.dtype[Any]
    hash: bytes

    @classmethod
    def from_dtype(cls, dtype: np.dtype[Any]) -> PoseFormat:
        desc = _describe(np.dtype(dtype))
        if desc["itemsize"] > MAX_POSE_ITEMSIZE:
            raise ProtocolError(f"pose dtype: itemsize {desc['itemsize']} too large")
        digest = hashlib.blake2b(_canonical(desc).encode(), digest_size=8).digest()
        return cls(_build(desc, "pose dtype"), digest)

    def to_json(self) -> dict[str, Any]:
        return {"descr": _describe(self.dtype), "hash": self.hash.hex()}

    @classmethod
    def from_json(cls, obj: object) -> PoseFormat:
        if not isinstance(obj, dict) or set(obj) != {"descr", "hash"}:
            raise _fail("hello.pose", "expected {descr, hash}", obj)
        fmt = cls.from_dtype(_build(obj["descr"], "hello.pose.descr"))
        if obj["hash"] != fmt.hash.hex():
            raise _fail(
                "hello.pose.hash", f"does not match the descr ({fmt.hash.hex()})", obj["hash"]
            )
        return fmt


# --------------------------------------------------------------------------------------------
# Bodies
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Hello:
    """HELLO/READY body: who is speaking and where its sockets are."""

    service: str
    role: str
    performer: int = 0
    endpoints: Mapping[str, str] = field(default_factory=dict)
    pose: PoseFormat | None = None
    protocol: int = PROTOCOL_VERSION

    def to_bytes(self) -> bytes:
        obj = {
            "service": self.service,
            "role": self.role,
            "protocol": self.protocol,
            "performer": self.performer,
            "endpoints": dict(self.endpoints),
            "pose": None if self.pose is None else self.pose.to_json(),
        }
        return json.dumps(obj, separators=(",", ":"), sort_keys=True).encode()

    @classmethod
    def from_bytes(cls, data: bytes) -> Hello:
        if len(data) > MAX_HELLO:
            raise _fail("hello", f"longer than {MAX_HELLO} bytes", len(data))
        try:
            obj = json.loads(data.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            raise _fail("hello", f"not UTF-8 JSON ({exc.__class__.__name__})", data[:40]) from exc
        keys = {"service", "role", "protocol", "performer", "endpoints", "pose"}
        if not isinstance(obj, dict) or set(obj) != keys:
            got = sorted(obj) if isinstance(obj, dict) else obj
            raise _fail("hello", f"expected keys {sorted(keys)}", got)
        for key in ("service", "role"):
            if not isinstance(obj[key], str) or not 0 < len(obj[key]) <= 200:
                raise _fail(f"hello.{key}", "expected a short string", obj[key])
        if obj["protocol"] != PROTOCOL_VERSION or type(obj["protocol"]) is not int:
            raise _fail("hello.protocol", f"expected {PROTOCOL_VERSION}", obj["protocol"])
        performer = obj["performer"]
        if type(performer) is not int or not 0 <= performer <= U16:
            raise _fail("hello.performer", "expected an integer 0..65535", performer)
        endpoints = obj["endpoints"]
        if not isinstance(endpoints, dict) or not all(
            isinstance(v, str) and len(v) < 1024 for v in endpoints.values()
        ):
            raise _fail("hello.endpoints", "expected {name: endpoint string}", endpoints)
        pose = None if obj["pose"] is None else PoseFormat.from_json(obj["pose"])
        return cls(obj["service"], obj["role"], performer, dict(endpoints), pose)


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


# --------------------------------------------------------------------------------------------
# Validation of row payloads (shared by encode and decode)
# --------------------------------------------------------------------------------------------


def _check_range(rows: np.ndarray, name: str, hi: int, lo: int = 0) -> None:
    col = rows[name]
    bad = (col < lo) | (col >= hi)
    if bad.any():
        i = int(np.argmax(bad))
        raise _fail(f"row {i}.{name}", f"out of range {lo}..{hi - 1}", int(col[i]))


def _check_time(rows: np.ndarray) -> None:
    bad = ~np.isfinite(rows["time_s"])
    if bad.any():
        i = int(np.argmax(bad))
        raise _fail(f"row {i}.time_s", "not finite", float(rows["time_s"][i]))


_ONSET_CODE_LIMITS = np.array(
    [128, 128, 16, len(INSTRUMENTS), len(ZONES), len(HIHATS)], np.uint8
)  # exclusive upper bounds of the u1 fields note … hihat (bytes 8..13 of a row)


def _onsets_ok(rows: np.ndarray) -> bool:
    """Fast path for the common case (all valid): a few whole-array operations."""
    raw = np.ascontiguousarray(rows).view(np.uint8).reshape(rows.size, ONSET_DTYPE.itemsize)
    codes = raw[:, 8:14]
    if (codes >= _ONSET_CODE_LIMITS).any() or not codes[:, 1].all():
        return False
    op = rows["openness"]
    with np.errstate(invalid="ignore"):
        in_range = (op >= 0) & (op <= 1)
    return bool(np.isfinite(rows["time_s"]).all() and (in_range | np.isnan(op)).all())


def check_onsets(rows: np.ndarray) -> None:
    if _onsets_ok(rows):
        return
    _check_time(rows)
    _check_range(rows, "note", 128)
    _check_range(rows, "velocity", 128, 1)
    _check_range(rows, "channel", 16)
    _check_range(rows, "instrument", len(INSTRUMENTS))
    _check_range(rows, "zone", len(ZONES))
    _check_range(rows, "hihat", len(HIHATS))
    op = rows["openness"]
    bad = ~np.isnan(op) & ~((op >= 0) & (op <= 1))
    if bad.any():
        i = int(np.argmax(bad))
        raise _fail(f"row {i}.openness", "expected NaN or 0..1", float(op[i]))


def check_controls(rows: np.ndarray) -> None:
    _check_time(rows)
    _check_range(rows, "kind", len(ControlKind))
    _check_range(rows, "channel", 16)
    _check_range(rows, "number", 128)
    _check_range(rows, "value", 128)


_ROW_CHECKS = {Kind.ONSET: check_onsets, Kind.CONTROL: check_controls}


def _rows_from(data: memoryview, dtype: np.dtype[Any], what: str) -> np.ndarray:
    size = len(data)
    if size == 0 or size % dtype.itemsize:
        raise _fail(
            f"{what} payload", f"not a whole number (>= 1) of {dtype.itemsize}-byte rows", size
        )
    n = size // dtype.itemsize
    if n > MAX_ROWS:
        raise _fail(f"{what} payload", f"more than {MAX_ROWS} rows", n)
    return np.frombuffer(data, dtype=dtype, count=n)


# --------------------------------------------------------------------------------------------
# Encode / decode
# --------------------------------------------------------------------------------------------


def encode(msg: Message, pose_format: PoseFormat | None = None) -> list[bytes]:
    """Frames for ``msg``; raises :class:`ProtocolError` if the message is not valid."""
    spec = SPECS.get(int(msg.kind))
    if spec is None:
        raise _fail("kind", "unknown", msg.kind)
    payload: list[bytes]
    body = msg.body
    if spec.layout == "json":
        if not isinstance(body, Hello):
            raise _fail("body", f"{spec.kind.name} needs a Hello", type(body).__name__)
        payload = [body.to_bytes()]
    elif spec.layout == "rows":
        assert spec.rows is not None
        if not isinstance(body, np.ndarray) or body.dtype != spec.rows or body.ndim != 1:
            got = body.dtype if isinstance(body, np.ndarray) else type(body).__name__
            raise _fail("body", f"{spec.kind.name} needs a 1-d {spec.rows} array", got)
        if not 0 < body.size <= MAX_ROWS:
            raise _fail("body", f"expected 1..{MAX_ROWS} rows", body.size)
        _ROW_CHECKS[spec.kind](body)
        payload = [np.ascontiguousarray(body).tobytes()]
    elif spec.layout == "pose":
        if pose_format is None:
            raise ProtocolError("pose: no pose format given to encode")
        if not isinstance(body, Pose) or body.rows.dtype != pose_format.dtype:
            raise _fail("body", "POSE needs a Pose of the announced dtype", type(body).__name__)
        n = body.rows.size
        if body.rows.ndim != 1 or not 0 < n <= MAX_ROWS or not math.isfinite(body.time_s):
            raise _fail("pose", "expected 1-d rows and a finite time", (n, body.time_s))
        head = POSE_HEADER.pack(pose_format.hash, n, body.time_s)
        payload = [head, np.ascontiguousarray(body.rows).tobytes()]
    elif spec.layout == "struct":
        if not isinstance(body, Gap):
            raise _fail("body", "GAP needs a Gap", type(body).__name__)
        if not 0 <= body.dropped <= U64 or body.reason not in set(GapReason):
            raise _fail("gap", "dropped or reason out of range", (body.dropped, body.reason))
        payload = [GAP_PAYLOAD.pack(body.dropped, body.first_time_s, body.last_time_s, body.reason)]
    else:
        if body is not None:
            raise _fail("body", "HEARTBEAT has no body", type(body).__name__)
        payload = [b""]
    total = sum(len(p) for p in payload)
    if total > MAX_PAYLOAD:
        raise _fail("payload_len", f"larger than {MAX_PAYLOAD}", total)
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
        raise _fail("flags", f"unknown bits (known mask {KNOWN_FLAGS:#x})", flags)
    if not 0 <= performer <= U16:
        raise _fail("performer", "out of range 0..65535", performer)
    if not 0 <= stream <= U16:
        raise _fail("stream", "out of range 0..65535", stream)
    if not 0 <= seq <= U64:
        raise _fail("seq", "out of range for u64", seq)
    if not math.isfinite(t):
        raise _fail("send_time_s", "not finite", t)


def _view(frame: object, index: int) -> memoryview:
    try:
        view = memoryview(frame)  # type: ignore[arg-type]
    except TypeError as exc:
        raise _fail(f"frame {index}", "not a bytes-like object", type(frame).__name__) from exc
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
        raise _fail("frames", "no frames", 0)
    head = _view(frames[0], 0)
    if len(head) != HEADER.size:
        raise _fail("header", f"expected {HEADER.size} bytes", len(head))
    magic, version, kind, flags, performer, stream, seq, t, length = HEADER.unpack(head)
    if magic != MAGIC:
        raise _fail("magic", f"expected {MAGIC!r}", magic)
    if version != PROTOCOL_VERSION:
        raise _fail("version", f"expected {PROTOCOL_VERSION}", version)
    spec = SPECS.get(kind)
    if spec is None:
        raise _fail("kind", f"unknown (known {sorted(SPECS)})", kind)
    _check_header_values(flags, performer, stream, seq, t)
    if length > max_payload:
        raise _fail("payload_len", f"larger than {max_payload}", length, "max_payload")
    if len(frames) != 1 + spec.frames:
        raise _fail("frames", f"{spec.kind.name} needs {1 + spec.frames} frames", len(frames))
    parts = [_view(f, i) for i, f in enumerate(frames[1:], start=1)]
    total = sum(len(p) for p in parts)
    if total != length:
        raise _fail("payload_len", f"header says {length}, frames hold {total}", length)
    body: Body
    if spec.layout == "json":
        body = Hello.from_bytes(parts[0].tobytes())
    elif spec.layout == "rows":
        assert spec.rows is not None
        body = _rows_from(parts[0], spec.rows, spec.kind.name)
        _ROW_CHECKS[spec.kind](body)
    elif spec.layout == "pose":
        body = _decode_pose(parts, pose_format)
    elif spec.layout == "struct":
        if len(parts[0]) != GAP_PAYLOAD.size:
            raise _fail("gap payload", f"expected {GAP_PAYLOAD.size} bytes", len(parts[0]))
        dropped, first, last, reason = GAP_PAYLOAD.unpack(parts[0])
        if reason not in GapReason._value2member_map_:
            raise _fail("gap.reason", "unknown", reason)
        if not (math.isfinite(first) and math.isfinite(last)):
            raise _fail("gap times", "not finite", (first, last))
        body = Gap(dropped, first, last, GapReason(reason))
    else:
        if len(parts[0]):
            raise _fail("heartbeat payload", "expected 0 bytes", len(parts[0]))
        body = None
    return Message(Kind(kind), body, performer, seq, t, stream, flags)


def _decode_pose(parts: list[memoryview], fmt: PoseFormat | None) -> Pose:
    if fmt is None:
        raise WireError("pose: no pose format was announced to this receiver (got a POSE)", "pose")
    if len(parts[0]) != POSE_HEADER.size:
        raise _fail("pose header", f"expected {POSE_HEADER.size} bytes", len(parts[0]))
    digest, n, time_s = POSE_HEADER.unpack(parts[0])
    if digest != fmt.hash:
        raise _fail("pose.hash", f"expected {fmt.hash.hex()}", digest.hex())
    if not math.isfinite(time_s):
        raise _fail("pose.time_s", "not finite", time_s)
    rows = _rows_from(parts[1], fmt.dtype, "POSE")
    if rows.size != n:
        raise _fail("pose.rows", f"header says {n}, payload holds {rows.size}", n)
    return Pose(time_s, rows)


# --------------------------------------------------------------------------------------------
# Sequence tracking
# --------------------------------------------------------------------------------------------


class SeqStatus(IntEnum):
    FIRST = 0  # first message seen on this stream
    OK = 1  # the expected next number
    GAP = 2  # numbers were skipped: ``missing`` messages lost
    DUPLICATE = 3  # an old number again (dropped by the caller)
    RESTART = 4  # 0 after higher numbers: the sender restarted


@dataclass(frozen=True, slots=True)
class SeqReport:
    status: SeqStatus
    missing: int = 0


@dataclass
class SeqStats:
    received: int = 0
    missing: int = 0
    duplicates: int = 0
    restarts: int = 0


class SequenceTracker:
    """Gap and duplicate detection per (performer, stream).

    A receiver joining mid-stream starts from whatever number it sees first (FIRST). ZeroMQ
    delivers in order on one connection, so a smaller number than expected is a duplicate,
    except 0, which means the sender restarted.
    """

    def __init__(self) -> None:
        self._next: dict[tuple[int, int], int] = {}
        self.stats: dict[tuple[int, int], SeqStats] = {}

    def reset(self) -> None:
        self._next.clear()
        self.stats.clear()

    def observe(self, performer: int, stream: int, seq: int) -> SeqReport:
        key = (performer, stream)
        stats = self.stats.setdefault(key, SeqStats())
        expected = self._next.get(key)
        if expected is None:
            report = SeqReport(SeqStatus.FIRST)
        elif seq == expected:
            report = SeqReport(SeqStatus.OK)
        elif seq > expected:
            report = SeqReport(SeqStatus.GAP, seq - expected)
            stats.missing += seq - expected
        elif seq == 0:
            report = SeqReport(SeqStatus.RESTART)
            stats.restarts += 1
        else:
            stats.duplicates += 1
            return SeqReport(SeqStatus.DUPLICATE)
        stats.received += 1
        self._next[key] = seq + 1
        return report

    def observe_message(self, msg: Message) -> SeqReport:
        return self.observe(msg.performer, msg.stream, msg.seq)
