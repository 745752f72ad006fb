"""Wire format: byte round trips, every validation path, fuzzing, sequence tracking."""

from __future__ import annotations

import re
import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from livedrummer import protocol as p
from livedrummer.errors import LivedrummerError, ProtocolError
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind

POSE_DTYPE = np.dtype(
    [
        ("time_s", "<f8"),
        ("joints", "<f4", (20, 4)),
        ("stick", [("tip", "<f4", (3,)), ("contact", "u1")]),
    ]
)


def onsets(n: int = 3) -> np.ndarray:
    rows = np.zeros(n, ONSET_DTYPE)
    rows["time_s"] = np.arange(n) * 0.125 + 10.0
    rows["note"] = 38
    rows["velocity"] = np.arange(n) % 127 + 1
    rows["channel"] = 9
    rows["instrument"] = 1
    rows["openness"] = np.nan
    rows["source"] = 7
    return rows


def controls(n: int = 2) -> np.ndarray:
    rows = np.zeros(n, CONTROL_DTYPE)
    rows["time_s"] = np.arange(n) * 0.01
    rows["kind"] = int(ControlKind.HIHAT_PEDAL)
    rows["number"] = 4
    rows["value"] = 90
    return rows


def hello(pose: p.PoseFormat | None = None) -> p.Hello:
    return p.Hello(
        "input", "source", 3, {"pub": "ipc:///tmp/x", "control": "tcp://127.0.0.1:5"}, pose
    )


# ---------------------------------------------------------------- round trips


def test_header_layout_is_the_documented_32_bytes() -> None:
    assert p.HEADER.size == 32
    frames = p.encode(p.Message(p.Kind.HEARTBEAT, None, 513, 2**40 + 5, 12.5, 2, 1))
    head = frames[0]
    assert head[:4] == b"LDRM"
    assert head[4] == p.PROTOCOL_VERSION
    assert head[5] == p.Kind.HEARTBEAT
    assert struct.unpack_from("<H", head, 6)[0] == 1
    assert struct.unpack_from("<H", head, 8)[0] == 513
    assert struct.unpack_from("<H", head, 10)[0] == 2
    assert struct.unpack_from("<Q", head, 12)[0] == 2**40 + 5
    assert struct.unpack_from("<d", head, 20)[0] == 12.5
    assert struct.unpack_from("<I", head, 28)[0] == 0
    assert frames[1] == b""
    assert head.startswith(p.topic(p.Kind.HEARTBEAT))


@pytest.mark.parametrize("kind,rows", [(p.Kind.ONSET, onsets(5)), (p.Kind.CONTROL, controls(3)),
                                       (p.Kind.SHOWN_ONSET, onsets(2)),
                                       (p.Kind.SHOWN_CONTROL, controls(2))])  # fmt: skip
def test_rows_round_trip_bytes_exactly(kind: p.Kind, rows: np.ndarray) -> None:
    msg = p.Message(kind, rows, performer=4, seq=99, send_time_s=3.25, flags=p.Flag.SIMULATED)
    frames = p.encode(msg)
    assert len(frames) == 2
    assert frames[1] == rows.tobytes()
    assert struct.unpack_from("<I", frames[0], 28)[0] == rows.nbytes
    back = p.decode(frames)
    assert (back.kind, back.performer, back.seq, back.send_time_s, back.flags) == (
        kind,
        4,
        99,
        3.25,
        1,
    )
    assert back.rows.tobytes() == rows.tobytes()
    assert p.encode(back) == frames


def test_onset_row_is_20_bytes_and_nan_openness_survives() -> None:
    rows = onsets(1)
    rows["instrument"] = INSTRUMENTS.index("hihat")
    rows["openness"] = 0.25
    back = p.decode(p.encode(p.Message(p.Kind.ONSET, rows))).rows
    assert ONSET_DTYPE.itemsize == 20
    assert back["openness"][0] == np.float32(0.25)
    assert np.isnan(p.decode(p.encode(p.Message(p.Kind.ONSET, onsets(1)))).rows["openness"][0])


def test_hello_ready_round_trip_with_pose_format() -> None:
    fmt = p.PoseFormat.from_dtype(POSE_DTYPE)
    for kind in (p.Kind.HELLO, p.Kind.READY):
        back = p.decode(p.encode(p.Message(kind, hello(fmt), performer=3)))
        assert back.kind == kind
        assert back.body == hello(fmt)
        assert isinstance(back.body, p.Hello)
        assert back.body.pose is not None and back.body.pose.dtype == POSE_DTYPE


def test_pose_round_trip_and_hash_check() -> None:
    fmt = p.PoseFormat.from_dtype(POSE_DTYPE)
    rows = np.zeros(2, POSE_DTYPE)
    rows["joints"] = np.arange(160, dtype=np.float32).reshape(2, 20, 4)
    rows["stick"]["contact"] = [0, 1]
    frames = p.encode(p.Message(p.Kind.POSE, p.Pose(7.5, rows), stream=p.Stream.POSES), fmt)
    assert len(frames) == 3
    back = p.decode(frames, fmt)
    assert isinstance(back.body, p.Pose)
    assert back.body.time_s == 7.5
    assert back.body.rows.tobytes() == rows.tobytes()
    other = p.PoseFormat.from_dtype(np.dtype([("time_s", "<f8"), ("joints", "<f4", (21, 4))]))
    assert other.hash != fmt.hash
    with pytest.raises(ProtocolError, match=r"pose\.hash"):
        p.decode(frames, other)
    with pytest.raises(ProtocolError, match="no pose format"):
        p.decode(frames)


def test_pose_format_hash_is_stable_and_descr_rebuilds_the_dtype() -> None:
    padded = np.dtype(
        {"names": ["a", "b"], "formats": ["<f4", ("<f4", (3,))], "offsets": [0, 8], "itemsize": 24}
    )
    for dt in (POSE_DTYPE, padded):
        fmt = p.PoseFormat.from_dtype(dt)
        again = p.PoseFormat.from_json(fmt.to_json())
        assert again.dtype == dt
        assert again.hash == fmt.hash == p.PoseFormat.from_dtype(dt).hash
    with pytest.raises(ProtocolError, match="hash"):
        p.PoseFormat.from_json({**p.PoseFormat.from_dtype(padded).to_json(), "hash": "00" * 8})


def test_pose_format_refuses_object_and_plain_dtypes() -> None:
    with pytest.raises(ProtocolError):
        p.PoseFormat.from_dtype(np.dtype([("o", object)]))
    with pytest.raises(ProtocolError):
        p.PoseFormat.from_dtype(np.dtype("<f4"))


def test_gap_round_trip() -> None:
    gap = p.Gap(12, 1.0, 2.5, p.GapReason.QUEUE_FULL)
    back = p.decode(p.encode(p.Message(p.Kind.GAP, gap, seq=4)))
    assert back.body == gap


# ---------------------------------------------------------------- validation


def good() -> list[bytes]:
    return p.encode(p.Message(p.Kind.ONSET, onsets(2), performer=1, seq=5, send_time_s=1.0))


def patch(frame: bytes, fmt: str, offset: int, value: object) -> bytes:
    b = bytearray(frame)
    struct.pack_into(fmt, b, offset, value)
    return bytes(b)


@pytest.mark.parametrize(
    "mutate,field",
    [
        (lambda f: [patch(f[0], "4s", 0, b"XXXX"), f[1]], "magic"),
        (lambda f: [patch(f[0], "B", 4, p.PROTOCOL_VERSION + 1), f[1]], "version"),
        (lambda f: [patch(f[0], "B", 5, 99), f[1]], "kind"),
        (lambda f: [patch(f[0], "H", 6, 0x80), f[1]], "flags"),
        (lambda f: [patch(f[0], "<d", 20, float("nan")), f[1]], "send_time_s"),
        (lambda f: [patch(f[0], "<I", 28, 47), f[1]], "payload_len"),
        (lambda f: [patch(f[0], "<I", 28, 2**31), f[1]], "payload_len"),
        (lambda f: [f[0][:31], f[1]], "header"),
        (lambda f: [f[0]], "frames"),
        (lambda f: [f[0], f[1], b""], "frames"),
        (lambda f: [patch(f[0], "<I", 28, 37), f[1][:37]], "ONSET payload"),
        (lambda f: [patch(f[0], "<I", 28, 0), b""], "ONSET payload"),
        (lambda f: [f[0], patch(f[1], "B", 8, 200)], "row 0.note"),
        (lambda f: [f[0], patch(f[1], "B", 9 + 20, 0)], "row 1.velocity"),
        (lambda f: [f[0], patch(f[1], "B", 10, 16)], "row 0.channel"),
        (lambda f: [f[0], patch(f[1], "B", 11, len(INSTRUMENTS))], "row 0.instrument"),
        (lambda f: [f[0], patch(f[1], "B", 12, len(ZONES))], "row 0.zone"),
        (lambda f: [f[0], patch(f[1], "B", 13, len(HIHATS))], "row 0.hihat"),
        (lambda f: [f[0], patch(f[1], "<f", 14, 1.5)], "row 0.openness"),
        (lambda f: [f[0], patch(f[1], "<d", 0, float("inf"))], "row 0.time_s"),
        (lambda f: [], "frames"),
        (lambda f: [f[0], 12], "frame 1"),
    ],
)
def test_decode_names_the_bad_field(mutate: object, field: str) -> None:
    frames = mutate(good())  # type: ignore[operator]
    with pytest.raises(ProtocolError, match=re.escape(field)) as info:
        p.decode(frames)
    assert isinstance(info.value, LivedrummerError)


def test_max_payload_is_enforced_before_parsing() -> None:
    frames = p.encode(p.Message(p.Kind.ONSET, onsets(100)))
    with pytest.raises(ProtocolError, match="payload_len"):
        p.decode(frames, max_payload=20 * 99)
    assert p.decode(frames, max_payload=20 * 100).rows.size == 100


def test_control_ranges_and_hello_json_checked() -> None:
    rows = controls(1)
    rows["kind"] = 9
    with pytest.raises(ProtocolError, match=r"row 0\.kind"):
        p.encode(p.Message(p.Kind.CONTROL, rows))
    head = p.encode(p.Message(p.Kind.HELLO, hello()))[0]
    for payload, field in [
        (b"\xff\xfe", "hello"),
        (b"[1,2]", "hello"),
        (b'{"service":"x"}', "hello"),
        (b"[" * 5000, "hello"),
    ]:
        frames = [patch(head, "<I", 28, len(payload)), payload]
        with pytest.raises(ProtocolError, match=field):
            p.decode(frames)
    now, other = p.PROTOCOL_VERSION, p.PROTOCOL_VERSION + 1
    bad = hello().to_bytes().replace(f'"protocol":{now}'.encode(), f'"protocol":{other}'.encode())
    with pytest.raises(ProtocolError, match=r"hello\.protocol"):
        p.decode([patch(head, "<I", 28, len(bad)), bad])


def test_encode_refuses_wrong_bodies() -> None:
    with pytest.raises(ProtocolError):
        p.encode(p.Message(p.Kind.ONSET, controls(1)))
    with pytest.raises(ProtocolError):
        p.encode(p.Message(p.Kind.ONSET, np.zeros(0, ONSET_DTYPE)))
    with pytest.raises(ProtocolError):
        p.encode(p.Message(p.Kind.HELLO, onsets(1)))
    with pytest.raises(ProtocolError):
        p.encode(p.Message(p.Kind.HEARTBEAT, onsets(1)))
    with pytest.raises(ProtocolError, match="performer"):
        p.encode(p.Message(p.Kind.HEARTBEAT, performer=70000))


# ---------------------------------------------------------------- fuzzing


def _all_valid_frames() -> list[list[bytes]]:
    fmt = p.PoseFormat.from_dtype(POSE_DTYPE)
    return [
        good(),
        p.encode(p.Message(p.Kind.CONTROL, controls(2))),
        p.encode(p.Message(p.Kind.SHOWN_CONTROL, controls(1), stream=p.Stream.POSES)),
        p.encode(p.Message(p.Kind.READY, hello(fmt))),
        p.encode(p.Message(p.Kind.POSE, p.Pose(1.0, np.zeros(1, POSE_DTYPE))), fmt),
        p.encode(p.Message(p.Kind.GAP, p.Gap(1, 0.0, 1.0, p.GapReason.SOURCE_LOST))),
        p.encode(p.Message(p.Kind.HEARTBEAT)),
    ]


VALID = _all_valid_frames()
FMT = p.PoseFormat.from_dtype(POSE_DTYPE)


def _decode_only_protocol_errors(frames: list[bytes]) -> None:
    try:
        p.decode(frames, FMT, max_payload=4096)
    except ProtocolError:
        pass


@settings(max_examples=400, deadline=None)
@given(st.lists(st.binary(max_size=80), max_size=4))
def test_fuzz_random_frames_raise_only_protocol_error(frames: list[bytes]) -> None:
    _decode_only_protocol_errors(frames)


@settings(max_examples=600, deadline=None)
@given(
    st.sampled_from(range(len(VALID))),
    st.data(),
)
def test_fuzz_mutated_valid_messages(which: int, data: st.DataObject) -> None:
    frames = [bytearray(f) for f in VALID[which]]
    action = data.draw(st.sampled_from(["flip", "truncate", "extend", "drop", "dup"]))
    i = data.draw(st.integers(0, len(frames) - 1))
    if action == "flip" and frames[i]:
        for _ in range(data.draw(st.integers(1, 4))):
            j = data.draw(st.integers(0, len(frames[i]) - 1))
            frames[i][j] ^= 1 << data.draw(st.integers(0, 7))
    elif action == "truncate":
        del frames[i][data.draw(st.integers(0, len(frames[i]))) :]
    elif action == "extend":
        frames[i] += data.draw(st.binary(min_size=1, max_size=5000))
    elif action == "drop":
        del frames[i]
    else:
        frames.insert(i, frames[i])
    _decode_only_protocol_errors([bytes(f) for f in frames])


@settings(max_examples=200, deadline=None)
@given(st.binary(min_size=0, max_size=300))
def test_fuzz_hello_payloads(payload: bytes) -> None:
    head = patch(VALID[2][0], "<I", 28, len(payload))
    _decode_only_protocol_errors([head, payload])


def test_oversized_message_is_refused() -> None:
    big = onsets(1000)
    frames = p.encode(p.Message(p.Kind.ONSET, big))
    with pytest.raises(ProtocolError, match="payload_len"):
        p.decode(frames, max_payload=1000)


# ---------------------------------------------------------------- sequence tracking


def test_sequence_tracker_reports_gaps_duplicates_restarts_per_stream() -> None:
    t = p.SequenceTracker()
    s_ = p.SeqStatus
    seen = [t.observe(1, 0, s).status for s in (5, 6, 7)]
    assert seen == [s_.FIRST, s_.OK, s_.OK]
    assert t.observe(2, 0, 0).status == s_.FIRST  # another performer, its own numbers
    assert t.observe(1, 1, 100).status == s_.FIRST  # another stream
    gap = t.observe(1, 0, 10)
    assert (gap.status, gap.missing) == (s_.GAP, 2)
    assert t.observe(1, 0, 9).status == s_.DUPLICATE
    assert t.observe(1, 0, 10).status == s_.DUPLICATE
    assert t.observe(1, 0, 11).status == s_.OK
    assert t.observe(1, 0, 0).status == s_.RESTART
    assert t.observe(1, 0, 1).status == s_.OK
    stats = t.stats[(1, 0)]
    assert (stats.received, stats.missing, stats.duplicates, stats.restarts) == (7, 2, 2, 1)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.booleans(), min_size=1, max_size=200))
def test_sequence_tracker_counts_exactly_what_was_dropped(kept: list[bool]) -> None:
    t = p.SequenceTracker()
    delivered = [s for s, k in enumerate(kept) if k]
    for s in delivered:
        t.observe(0, 0, s)
    if delivered:
        stats = t.stats[(0, 0)]
        assert stats.received == len(delivered)
        assert stats.missing == delivered[-1] - delivered[0] + 1 - len(delivered)


def test_the_documented_schema_matches_the_table() -> None:
    doc = p.__doc__ or ""
    rows = {}
    for line in doc.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0] in p.Kind.__members__ and parts[1].isdigit():
            rows[parts[0]] = (int(parts[1]), int(parts[2]))
    assert rows == {s.kind.name: (int(s.kind), s.frames) for s in p.SPECS.values()}
    assert f"little-endian, {p.HEADER.size} bytes" in doc
    assert f"{p.POSE_HEADER.size} bytes" in doc and f"{p.GAP_PAYLOAD.size} bytes" in doc
    assert (
        f"({ONSET_DTYPE.itemsize} bytes each)" in doc
        and f"({CONTROL_DTYPE.itemsize} bytes each)" in doc
    )


JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-5, 70000)
    | st.floats()
    | st.sampled_from(["<f4", "|V4", "u1", "O", "x"]),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.sampled_from(
                ["names", "formats", "offsets", "itemsize", "type", "shape", "struct", "a"]
            ),
            inner,
            max_size=5,
        )
    ),
    max_leaves=30,
)


@settings(max_examples=150, deadline=None)
@given(JSON, st.text(max_size=20))
def test_fuzz_pose_format_descriptions(descr: object, digest: str) -> None:
    try:
        p.PoseFormat.from_json({"descr": descr, "hash": digest})
    except ProtocolError:
        pass


FIELD = st.fixed_dictionaries(
    {
        "type": st.sampled_from(["<f4", "<f8", "u1", "|V3", ">i2", "O", "<U4", "<f4x"]),
        "shape": st.lists(st.integers(-1, 5), max_size=3),
    }
)


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.text(min_size=0, max_size=3), min_size=0, max_size=4),
    st.lists(FIELD, max_size=4),
    st.lists(st.integers(-2, 64), max_size=4),
    st.integers(-1, 200),
)
def test_fuzz_structured_pose_descriptions(
    names: list[str], formats: list[object], offsets: list[int], itemsize: int
) -> None:
    descr = {"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize}
    try:
        fmt = p.PoseFormat.from_json({"descr": descr, "hash": "0" * 16})
    except ProtocolError:
        return
    raise AssertionError(f"accepted a wrong hash for {fmt.dtype}")
