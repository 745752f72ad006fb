"""The session journal's record format: append-only, length-prefixed, CRC-checked.

Why this shape. The journal exists so that nothing played is lost, even when the input daemon
is killed mid-write or the machine loses power. So each batch of events is one self-checking
record appended with one ``write``: a crash can only tear the *last* record, and the reader
recognises a torn tail (short prefix, length past the end, or a CRC that does not match) and
stops there, reporting how many bytes it discarded, instead of failing the whole session.
Rows are the same numpy record bytes as on the wire (:mod:`livedrummer.timeline.events`), so
writing is a copy and reading is ``frombuffer``; the one JSON record (session metadata) is
written once. The rows are checked by the wire's row checks and a gap is the wire's GAP
payload: the journal is the stream written to disk, so it lives beside the wire format.

Layout (little-endian)::

    file header  16 bytes: magic b"LDJOURNL", version u16 (1), 6 reserved zero bytes
    record       prefix <II: body_len u32, crc32(body) u32
                 body   <B3xIdQ: kind u8, 3 pad, count u32, arrival_s f64, first_seq u64
                        + payload (body_len - 24 bytes)

    kind      payload                               count
    META  1   UTF-8 JSON object (first record)      0
    ONSETS 2  count rows of events.ONSET_DTYPE      rows
    CONTROLS 3 count rows of events.CONTROL_DTYPE   rows
    GAP   4   protocol.GAP_PAYLOAD                  events dropped
    END   5   UTF-8 JSON object (clean close)       0

``arrival_s`` is when the batch reached the daemon on the shared clock (livedrummer.timeline.clock);
``first_seq`` the wire sequence number the batch was published under, so a journal and a
subscriber's log can be matched. A record's CRC covers its whole body.

Limits: a record is at most :data:`MAX_RECORD` bytes. Corruption *inside* the file (not at
the tail) also stops the reader, at the first bad record: records have no resync marker,
since after a crash only the tail can be torn. What the writer flushes when is its own
policy (``services/input/journal.py``).
"""

from __future__ import annotations

import json
import struct
import zlib
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np

from livedrummer.errors import JournalError, ProtocolError
from livedrummer.protocol.bodies import Gap
from livedrummer.protocol.rows import check_controls, check_onsets
from livedrummer.protocol.spec import GAP_PAYLOAD, GapReason
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE

MAGIC = b"LDJOURNL"
VERSION = 1
FILE_HEADER = struct.Struct("<8sH6x")
PREFIX = struct.Struct("<II")
BODY = struct.Struct("<B3xIdQ")
MAX_RECORD = 64 * 1024 * 1024
SUFFIX = ".ldj"


class RecordKind(IntEnum):
    META = 1
    ONSETS = 2
    CONTROLS = 3
    GAP = 4
    END = 5


def file_header() -> bytes:
    return FILE_HEADER.pack(MAGIC, VERSION)


def _record(
    kind: RecordKind, count: int, arrival_s: float, first_seq: int, payload: bytes
) -> bytes:
    body = BODY.pack(int(kind), count, arrival_s, first_seq) + payload
    if len(body) > MAX_RECORD:
        raise JournalError(f"journal record of {len(body)} bytes exceeds {MAX_RECORD}")
    return PREFIX.pack(len(body), zlib.crc32(body)) + body


def meta_record(meta: dict[str, Any]) -> bytes:
    return _record(RecordKind.META, 0, 0.0, 0, json.dumps(meta, sort_keys=True).encode())


def end_record(info: dict[str, Any], time_s: float) -> bytes:
    return _record(RecordKind.END, 0, time_s, 0, json.dumps(info, sort_keys=True).encode())


def onsets_record(rows: np.ndarray, arrival_s: float, first_seq: int) -> bytes:
    if rows.dtype != ONSET_DTYPE:
        raise JournalError(f"onset rows must have ONSET_DTYPE (got {rows.dtype})")
    return _record(RecordKind.ONSETS, rows.size, arrival_s, first_seq, rows.tobytes())


def controls_record(rows: np.ndarray, arrival_s: float, first_seq: int) -> bytes:
    if rows.dtype != CONTROL_DTYPE:
        raise JournalError(f"control rows must have CONTROL_DTYPE (got {rows.dtype})")
    return _record(RecordKind.CONTROLS, rows.size, arrival_s, first_seq, rows.tobytes())


def gap_record(gap: Gap, arrival_s: float, first_seq: int) -> bytes:
    payload = GAP_PAYLOAD.pack(gap.dropped, gap.first_time_s, gap.last_time_s, int(gap.reason))
    return _record(RecordKind.GAP, min(gap.dropped, 0xFFFFFFFF), arrival_s, first_seq, payload)


@dataclass
class Journal:
    """Everything a journal file held up to its last intact record."""

    name: str
    meta: dict[str, Any] | None
    onsets: np.ndarray
    controls: np.ndarray
    onset_arrivals_s: np.ndarray  # per onset row: arrival time of its batch
    gaps: list[Gap] = field(default_factory=list)
    end: dict[str, Any] | None = None  # present when the writer closed cleanly
    records: int = 0
    discarded_bytes: int = 0
    stop_reason: str = ""  # "" (read to the end) or why reading stopped early

    @property
    def clean(self) -> bool:
        return self.end is not None and not self.discarded_bytes


def _json(payload: bytes, name: str, pos: int) -> dict[str, Any]:
    try:
        obj = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise JournalError(f"{name}: byte {pos}: metadata is not JSON ({exc})") from exc
    if not isinstance(obj, dict):
        raise JournalError(f"{name}: byte {pos}: metadata is not a JSON object")
    return obj


def read_journal(data: bytes, name: str) -> Journal:
    """Parse a journal's bytes; stop cleanly at a torn or corrupt record (see module docstring)."""
    if len(data) < FILE_HEADER.size:
        raise JournalError(f"{name}: {len(data)} bytes, shorter than the journal header")
    magic, version = FILE_HEADER.unpack_from(data)
    if magic != MAGIC:
        raise JournalError(f"{name}: byte 0: not a livedrummer journal (starts {magic!r})")
    if version != VERSION:
        raise JournalError(f"{name}: byte 8: journal version {version}, expected {VERSION}")
    pos = FILE_HEADER.size
    onsets: list[np.ndarray] = []
    arrivals: list[np.ndarray] = []
    controls: list[np.ndarray] = []
    out = Journal(name, None, np.zeros(0, ONSET_DTYPE), np.zeros(0, CONTROL_DTYPE), np.zeros(0))
    view = memoryview(data)
    while pos < len(data):
        reason = ""
        if len(data) - pos < PREFIX.size:
            reason = f"torn record prefix at byte {pos}"
        else:
            length, crc = PREFIX.unpack_from(data, pos)
            end = pos + PREFIX.size + length
            if length < BODY.size or length > MAX_RECORD:
                reason = f"bad record length {length} at byte {pos}"
            elif end > len(data):
                present = len(data) - pos - PREFIX.size
                reason = f"torn record at byte {pos} ({length} bytes declared, {present} present)"
            elif zlib.crc32(view[pos + PREFIX.size : end]) != crc:
                where = "torn last record" if end == len(data) else "corrupt record"
                reason = f"{where} at byte {pos} (CRC mismatch)"
        if reason:
            out.discarded_bytes = len(data) - pos
            out.stop_reason = reason
            break
        body = pos + PREFIX.size
        kind, count, arrival_s, _seq = BODY.unpack_from(data, body)
        payload = view[body + BODY.size : end]
        _take(out, kind, count, arrival_s, payload, pos, onsets, arrivals, controls)
        out.records += 1
        pos = end
    if onsets:
        out.onsets = np.concatenate(onsets)
        out.onset_arrivals_s = np.concatenate(arrivals)
    if controls:
        out.controls = np.concatenate(controls)
    return out


def _take(
    out: Journal,
    kind: int,
    count: int,
    arrival_s: float,
    payload: memoryview,
    pos: int,
    onsets: list[np.ndarray],
    arrivals: list[np.ndarray],
    controls: list[np.ndarray],
) -> None:
    name = out.name
    if kind == RecordKind.META:
        out.meta = _json(payload.tobytes(), name, pos)
    elif kind == RecordKind.END:
        out.end = _json(payload.tobytes(), name, pos)
    elif kind in (RecordKind.ONSETS, RecordKind.CONTROLS):
        dtype = ONSET_DTYPE if kind == RecordKind.ONSETS else CONTROL_DTYPE
        if len(payload) != count * dtype.itemsize:
            raise JournalError(f"{name}: byte {pos}: {count} rows but {len(payload)} bytes")
        rows = np.frombuffer(payload, dtype=dtype, count=count)
        try:
            (check_onsets if kind == RecordKind.ONSETS else check_controls)(rows)
        except ProtocolError as exc:
            raise JournalError(f"{name}: byte {pos}: {exc}") from exc
        if kind == RecordKind.ONSETS:
            onsets.append(rows)
            arrivals.append(np.full(count, arrival_s))
        else:
            controls.append(rows)
    elif kind == RecordKind.GAP:
        if len(payload) != GAP_PAYLOAD.size:
            raise JournalError(f"{name}: byte {pos}: gap record of {len(payload)} bytes")
        dropped, first, last, reason = GAP_PAYLOAD.unpack(payload)
        if reason not in GapReason._value2member_map_:
            raise JournalError(f"{name}: byte {pos}: unknown gap reason {reason}")
        out.gaps.append(Gap(dropped, first, last, GapReason(reason)))
    else:
        raise JournalError(f"{name}: byte {pos}: unknown record kind {kind}")
