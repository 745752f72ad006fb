"""Tests for livedrummer.midi.stream (incremental MIDI 1.0 byte-stream parser)."""

from __future__ import annotations

from dataclasses import astuple

import mido
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from livedrummer.midi.stream import MidiMessage, MidiStreamParser, ParserStats

M = MidiMessage

REALTIME = (0xF8, 0xFA, 0xFB, 0xFC, 0xFE, 0xFF)
UNDEFINED = (0xF4, 0xF5, 0xF9, 0xFD)


def parse(data: bytes, **kw: int) -> tuple[list[MidiMessage], ParserStats]:
    p = MidiStreamParser(**kw)
    return p.feed(data), p.stats


def parse_bytewise(data: bytes, **kw: int) -> tuple[list[MidiMessage], ParserStats]:
    p = MidiStreamParser(**kw)
    out: list[MidiMessage] = []
    for b in data:
        out.extend(p.feed(bytes((b,))))
    return out, p.stats


# --------------------------------------------------------------------------
# Hand-written sequences
# --------------------------------------------------------------------------


def test_single_note_on() -> None:
    msgs, stats = parse(bytes([0x99, 38, 100]))
    assert msgs == [M(0x99, bytes([38, 100]), 0)]
    m = msgs[0]
    assert (m.kind, m.channel, m.note, m.velocity) == ("note_on", 9, 38, 100)
    assert m.control is None and m.value is None
    assert stats == ParserStats(bytes_in=3, messages=1)


def test_running_status_across_many_notes() -> None:
    notes = [(36 + i % 12, 1 + (i * 7) % 127) for i in range(200)]
    data = bytearray([0x99])
    for n, v in notes:
        data += bytes([n, v])
    msgs, stats = parse(bytes(data))
    assert len(msgs) == 200
    for i, (m, (n, v)) in enumerate(zip(msgs, notes, strict=True)):
        assert m == M(0x99, bytes([n, v]), 0 if i == 0 else 1 + 2 * i)
    assert stats.running_status_used == 199
    assert stats.garbage_bytes == 0
    assert msgs == parse_bytewise(bytes(data))[0]


def test_running_status_single_data_byte_messages() -> None:
    msgs, stats = parse(bytes([0xC3, 5, 6, 7, 0xD3, 100, 90]))
    assert [(m.kind, m.channel, m.value, m.offset) for m in msgs] == [
        ("program_change", 3, 5, 0),
        ("program_change", 3, 6, 2),
        ("program_change", 3, 7, 3),
        ("aftertouch", 3, 100, 4),
        ("aftertouch", 3, 90, 6),
    ]
    assert stats.running_status_used == 3


def test_new_channel_status_replaces_running_status() -> None:
    msgs, _ = parse(bytes([0x90, 60, 1, 61, 2, 0xB0, 4, 90, 4, 80, 0x80, 60, 64]))
    assert [(m.kind, m.data) for m in msgs] == [
        ("note_on", bytes([60, 1])),
        ("note_on", bytes([61, 2])),
        ("control_change", bytes([4, 90])),
        ("control_change", bytes([4, 80])),
        ("note_off", bytes([60, 64])),
    ]
    assert msgs[2].control == 4 and msgs[2].value == 90


def test_clock_bytes_between_note_data_bytes() -> None:
    data = bytes([0x99, 0xF8, 38, 0xF8, 100, 42, 0xFE, 90, 0xF8])
    msgs, stats = parse(data)
    assert msgs == [
        M(0xF8, b"", 1),
        M(0xF8, b"", 3),
        M(0x99, bytes([38, 100]), 0),
        M(0xFE, b"", 6),
        M(0x99, bytes([42, 90]), 5),
        M(0xF8, b"", 8),
    ]
    assert stats.garbage_bytes == 0
    assert stats.running_status_used == 1
    assert parse_bytewise(data) == (msgs, stats)


def test_realtime_does_not_clear_running_status() -> None:
    msgs, stats = parse(bytes([0x90, 60, 100, 0xFA, 0xFC, 0xFF, 61, 100]))
    assert [m.kind for m in msgs] == ["note_on", "start", "stop", "reset", "note_on"]
    assert msgs[-1].offset == 6
    assert stats.garbage_bytes == 0


@pytest.mark.parametrize(
    ("byte", "kind"),
    [
        (0xF8, "clock"),
        (0xFA, "start"),
        (0xFB, "continue"),
        (0xFC, "stop"),
        (0xFE, "active_sensing"),
        (0xFF, "reset"),
    ],
)
def test_realtime_kinds(byte: int, kind: str) -> None:
    (m,) = parse(bytes([byte]))[0]
    assert m.kind == kind and m.channel is None and m.data == b""
    assert m.to_mido() == mido.Message(kind)


def test_sysex() -> None:
    data = bytes([0xF0, 0x7E, 0x7F, 0x06, 0x01, 0xF7])
    msgs, stats = parse(data)
    assert msgs == [M(0xF0, bytes([0x7E, 0x7F, 0x06, 0x01]), 0)]
    assert msgs[0].kind == "sysex"
    assert msgs[0].to_mido() == mido.Message("sysex", data=[0x7E, 0x7F, 0x06, 0x01])
    assert msgs[0].to_bytes() == data
    assert stats.garbage_bytes == 0 and stats.sysex_truncated == 0


def test_empty_sysex_and_realtime_inside_sysex() -> None:
    msgs, stats = parse(bytes([0xF0, 0xF7, 0xF0, 1, 0xF8, 2, 0xF7]))
    assert msgs == [M(0xF0, b"", 0), M(0xF8, b"", 4), M(0xF0, bytes([1, 2]), 2)]
    assert stats.garbage_bytes == 0


def test_sysex_clears_running_status() -> None:
    msgs, stats = parse(bytes([0x90, 60, 100, 0xF0, 1, 0xF7, 61, 100]))
    assert [m.kind for m in msgs] == ["note_on", "sysex"]
    assert stats.garbage_bytes == 2


def test_unterminated_sysex_ended_by_status_is_truncated() -> None:
    msgs, stats = parse(bytes([0xF0, 1, 2, 3, 0x99, 38, 100]))
    assert msgs == [M(0xF0, bytes([1, 2, 3]), 0), M(0x99, bytes([38, 100]), 4)]
    assert stats.sysex_truncated == 1
    assert stats.garbage_bytes == 0


def test_sysex_ended_by_another_sysex() -> None:
    msgs, stats = parse(bytes([0xF0, 1, 0xF0, 2, 0xF7]))
    assert msgs == [M(0xF0, bytes([1]), 0), M(0xF0, bytes([2]), 2)]
    assert stats.sysex_truncated == 1


def test_unterminated_sysex_is_held_until_more_bytes() -> None:
    p = MidiStreamParser()
    assert p.feed(bytes([0xF0, 1, 2])) == []
    assert p.feed(bytes([3, 0xF7])) == [M(0xF0, bytes([1, 2, 3]), 0)]


def test_sysex_at_max_length_is_kept() -> None:
    data = bytes([0xF0, *range(8), 0xF7])
    msgs, stats = parse(data, max_sysex=8)
    assert msgs == [M(0xF0, bytes(range(8)), 0)]
    assert stats.sysex_too_long == 0


def test_sysex_too_long_is_discarded_and_counted() -> None:
    data = bytes([0xF0, *range(9), 0xF7, 0x99, 38, 100])
    msgs, stats = parse(data, max_sysex=8)
    assert msgs == [M(0x99, bytes([38, 100]), 11)]
    assert stats.sysex_too_long == 1
    assert stats.garbage_bytes == 11  # F0 + 9 payload bytes + F7
    assert parse_bytewise(data, max_sysex=8) == (msgs, stats)


def test_sysex_too_long_ended_by_status() -> None:
    data = bytes([0xF0, *([5] * 20), 0xF8, 0x90, 60, 100])
    msgs, stats = parse(data, max_sysex=4)
    assert msgs == [M(0xF8, b"", 21), M(0x90, bytes([60, 100]), 22)]
    assert stats.sysex_too_long == 1
    assert stats.sysex_truncated == 0
    assert stats.garbage_bytes == 21


def test_default_max_sysex() -> None:
    ok = bytes([0xF0, *([1] * 4096), 0xF7])
    bad = bytes([0xF0, *([1] * 4097), 0xF7])
    assert len(parse(ok)[0]) == 1
    msgs, stats = parse(bad)
    assert msgs == [] and stats.sysex_too_long == 1


def test_max_sysex_must_not_be_negative() -> None:
    with pytest.raises(ValueError):
        MidiStreamParser(max_sysex=-1)


def test_system_common_lengths() -> None:
    data = bytes([0xF1, 0x23, 0xF2, 0x10, 0x02, 0xF3, 7, 0xF6])
    msgs, stats = parse(data)
    assert msgs == [
        M(0xF1, bytes([0x23]), 0),
        M(0xF2, bytes([0x10, 0x02]), 2),
        M(0xF3, bytes([7]), 5),
        M(0xF6, b"", 7),
    ]
    assert [m.kind for m in msgs] == [
        "quarter_frame",
        "songpos",
        "song_select",
        "tune_request",
    ]
    assert msgs[1].value == 0x10 | (0x02 << 7)
    assert msgs[0].to_mido() == mido.Message("quarter_frame", frame_type=2, frame_value=3)
    assert msgs[1].to_mido() == mido.Message("songpos", pos=0x110)
    assert msgs[2].to_mido() == mido.Message("song_select", song=7)
    assert msgs[3].to_mido() == mido.Message("tune_request")
    assert stats.garbage_bytes == 0


def test_system_common_clears_running_status() -> None:
    msgs, stats = parse(bytes([0x90, 60, 100, 0xF6, 61, 100, 0xF3, 1, 2]))
    assert [m.kind for m in msgs] == ["note_on", "tune_request", "song_select"]
    assert stats.garbage_bytes == 3  # 61 100 after F6, 2 after F3 1


def test_interrupted_message_is_garbage() -> None:
    data = bytes([0x90, 60, 0xB0, 4, 0x80, 60, 64])
    msgs, stats = parse(data)
    assert msgs == [M(0x80, bytes([60, 64]), 4)]
    assert stats.garbage_bytes == 4  # 90 3C, B0 04


def test_interrupted_running_status_message_counts_only_data_bytes() -> None:
    msgs, stats = parse(bytes([0x90, 60, 100, 61, 0x90, 62, 100]))
    assert msgs == [M(0x90, bytes([60, 100]), 0), M(0x90, bytes([62, 100]), 4)]
    assert stats.garbage_bytes == 1


def test_stray_data_bytes_are_garbage() -> None:
    msgs, stats = parse(bytes([1, 2, 3, 0x99, 38, 100]))
    assert msgs == [M(0x99, bytes([38, 100]), 3)]
    assert stats.garbage_bytes == 3
    assert stats.running_status_used == 0


@pytest.mark.parametrize("undefined", UNDEFINED)
def test_undefined_status_is_garbage(undefined: int) -> None:
    msgs, stats = parse(bytes([undefined, 1, 0x99, 38, 100]))
    assert msgs == [M(0x99, bytes([38, 100]), 2)]
    assert stats.garbage_bytes == 2


def test_undefined_system_common_clears_running_status() -> None:
    msgs, stats = parse(bytes([0x99, 38, 100, 0xF5, 38, 100]))
    assert len(msgs) == 1
    assert stats.garbage_bytes == 3


def test_undefined_realtime_neither_interrupts_nor_clears() -> None:
    msgs, stats = parse(bytes([0x99, 38, 0xF9, 100, 0xFD, 40, 90]))
    assert msgs == [M(0x99, bytes([38, 100]), 0), M(0x99, bytes([40, 90]), 5)]
    assert stats.garbage_bytes == 2


def test_stray_eox_is_garbage() -> None:
    msgs, stats = parse(bytes([0xF7, 0x90, 60, 1]))
    assert msgs == [M(0x90, bytes([60, 1]), 1)]
    assert stats.garbage_bytes == 1


def test_note_on_velocity_zero_is_note_off() -> None:
    msgs, _ = parse(bytes([0x95, 60, 100, 60, 0, 0x95, 61, 0]))
    assert msgs == [
        M(0x95, bytes([60, 100]), 0),
        M(0x85, bytes([60, 0]), 3, note_on_vel0=True),
        M(0x85, bytes([61, 0]), 5, note_on_vel0=True),
    ]
    off = msgs[1]
    assert (off.kind, off.channel, off.note, off.velocity) == ("note_off", 5, 60, 0)
    assert off.to_mido() == mido.Message("note_off", channel=5, note=60, velocity=0)
    assert off.to_mido(as_sent=True) == mido.Message("note_on", channel=5, note=60, velocity=0)


def test_real_note_off_is_not_flagged() -> None:
    (m,) = parse(bytes([0x80, 60, 0]))[0]
    assert m == M(0x80, bytes([60, 0]), 0) and not m.note_on_vel0


def test_offsets_span_feeds_and_reset() -> None:
    p = MidiStreamParser()
    assert p.feed(bytes([0xF8, 0x90])) == [M(0xF8, b"", 0)]
    assert p.feed(bytes([60])) == []
    assert p.feed(bytes([100, 61, 100])) == [
        M(0x90, bytes([60, 100]), 1),
        M(0x90, bytes([61, 100]), 4),
    ]
    assert p.stats.bytes_in == 6
    p.reset()
    assert p.stats == ParserStats()
    # Running status is forgotten by reset: these are stray data bytes.
    assert p.feed(bytes([62, 100, 0xFE])) == [M(0xFE, b"", 2)]
    assert p.stats.garbage_bytes == 2


def test_feed_accepts_bytearray_and_memoryview() -> None:
    data = bytes([0x99, 38, 100, 40, 90])
    expected = parse(data)[0]
    assert MidiStreamParser().feed(bytearray(data)) == expected
    assert MidiStreamParser().feed(memoryview(data)) == expected


def test_message_properties() -> None:
    pb = M(0xE2, bytes([0x00, 0x40]), 0)
    assert (pb.kind, pb.channel, pb.value) == ("pitchwheel", 2, 0)
    assert M(0xE0, bytes([0, 0]), 0).value == -8192
    assert M(0xE0, bytes([0x7F, 0x7F]), 0).value == 8191
    assert pb.to_mido() == mido.Message("pitchwheel", channel=2, pitch=0)
    pt = M(0xA9, bytes([46, 127]), 0)
    assert (pt.kind, pt.note, pt.value, pt.velocity) == ("polytouch", 46, 127, None)
    cc = M(0xB9, bytes([4, 127]), 0)
    assert cc.to_mido() == mido.Message("control_change", channel=9, control=4, value=127)
    assert M(0xF8, b"", 0).note is None
    assert M(0xF4, b"", 0).kind == "unknown"


def test_never_raises_on_all_byte_values() -> None:
    data = bytes(range(256)) * 4 + bytes(range(255, -1, -1)) * 4
    msgs, stats = parse(data)
    assert parse_bytewise(data) == (msgs, stats)
    assert stats.bytes_in == len(data)


# --------------------------------------------------------------------------
# Property-based tests
# --------------------------------------------------------------------------

# A "spec" is (status, data) of a valid message, status as sent on the wire.
Spec = tuple[int, bytes]

data7 = st.integers(0, 127)


def channel_data(draw: st.DrawFn, status: int) -> bytes:
    hi = status & 0xF0
    n = 1 if hi in (0xC0, 0xD0) else 2
    data = bytes(draw(st.lists(data7, min_size=n, max_size=n)))
    if hi == 0x90 and draw(st.booleans()):
        data = data[:1] + b"\x00"  # make vel-0 note-ons common
    return data


@st.composite
def channel_msg(draw: st.DrawFn) -> Spec:
    hi = draw(st.sampled_from([0x80, 0x90, 0xA0, 0xB0, 0xC0, 0xD0, 0xE0]))
    status = hi | draw(st.integers(0, 15))
    return status, channel_data(draw, status)


@st.composite
def common_msg(draw: st.DrawFn) -> Spec:
    status = draw(st.sampled_from([0xF1, 0xF2, 0xF3, 0xF6]))
    n = {0xF1: 1, 0xF2: 2, 0xF3: 1, 0xF6: 0}[status]
    return status, bytes(draw(st.lists(data7, min_size=n, max_size=n)))


sysex_msg = st.builds(lambda payload: (0xF0, bytes(payload)), st.lists(data7, max_size=40))
realtime_msg = st.builds(lambda b: (b, b""), st.sampled_from(REALTIME))
valid_msg = st.one_of(
    channel_msg(), channel_msg(), channel_msg(), common_msg(), sysex_msg, realtime_msg
)


def expected_message(status: int, data: bytes, offset: int) -> MidiMessage:
    if status & 0xF0 == 0x90 and data[1] == 0:
        return M(status - 0x10, data, offset, note_on_vel0=True)
    return M(status, data, offset)


class Encoder:
    """Builds a stream together with the messages a correct parser emits."""

    def __init__(self, draw: st.DrawFn) -> None:
        self.draw = draw
        self.buf = bytearray()
        self.running = 0  # running status the parser should hold
        self.omitted = 0  # messages sent with running status
        # (emission position, message): a message is emitted on its last byte
        self.emitted: list[tuple[int, MidiMessage]] = []

    def _realtime(self) -> None:
        if self.draw(st.integers(0, 3)) == 0:
            b = self.draw(st.sampled_from(REALTIME))
            self.emitted.append((len(self.buf), M(b, b"", len(self.buf))))
            self.buf.append(b)

    def add(self, spec: Spec, *, force_status: bool = False) -> MidiMessage:
        status, data = spec
        if status >= 0xF8:
            self.emitted.append((len(self.buf), M(status, b"", len(self.buf))))
            self.buf.append(status)
            return self.emitted[-1][1]
        tokens: list[int] = []
        omit = (
            not force_status
            and status < 0xF0
            and status == self.running
            and self.draw(st.booleans())
        )
        if omit:
            self.omitted += 1
        else:
            tokens.append(status)
        if status == 0xF0:
            tokens += [*data, 0xF7]
        else:
            tokens += data
        self.running = status if status < 0xF0 else 0
        start = len(self.buf)
        for i, t in enumerate(tokens):
            if i:
                self._realtime()
            self.buf.append(t)
        msg = expected_message(status, data, start)
        self.emitted.append((len(self.buf) - 1, msg))
        return msg

    def add_raw(self, raw: bytes) -> None:
        self.buf += raw
        self.running = -1  # unknown after garbage: force an explicit status

    def messages(self) -> list[MidiMessage]:
        return [m for _, m in sorted(self.emitted, key=lambda pm: pm[0])]


@st.composite
def valid_stream(draw: st.DrawFn) -> tuple[bytes, list[MidiMessage], int]:
    enc = Encoder(draw)
    for _ in range(draw(st.integers(0, 60))):
        if enc.running > 0 and draw(st.integers(0, 2)):
            # repeat the status (a drum roll): running status is likely
            spec = (enc.running, channel_data(draw, enc.running))
        else:
            spec = draw(valid_msg)
        enc.add(spec)
    return bytes(enc.buf), enc.messages(), enc.omitted


def split_points(dd: st.DataObject, n: int) -> list[int]:
    cuts = dd.draw(st.lists(st.integers(0, n), max_size=12))
    return sorted(cuts)


def feed_in_chunks(
    data: bytes, cuts: list[int], **kw: int
) -> tuple[list[MidiMessage], ParserStats]:
    p = MidiStreamParser(**kw)
    out: list[MidiMessage] = []
    prev = 0
    for c in [*cuts, len(data)]:
        out += p.feed(data[prev:c])
        prev = c
    return out, p.stats


@given(valid_stream())
@settings(max_examples=300)
def test_property_valid_stream_round_trips(
    stream: tuple[bytes, list[MidiMessage], int],
) -> None:
    data, expected, omitted = stream
    msgs, stats = parse(data)
    assert msgs == expected
    assert stats.running_status_used == omitted
    assert stats.garbage_bytes == 0
    assert stats.messages == len(expected)
    assert stats.bytes_in == len(data)
    assert stats.sysex_truncated == 0 and stats.sysex_too_long == 0


@given(valid_stream(), st.data())
@settings(max_examples=300)
def test_property_chunking_is_invisible(
    stream: tuple[bytes, list[MidiMessage], int], dd: st.DataObject
) -> None:
    data, expected, _ = stream
    out, stats = feed_in_chunks(data, split_points(dd, len(data)))
    assert out == expected
    assert stats == parse(data)[1]


garbage_byte = st.one_of(data7, st.sampled_from(UNDEFINED))


@st.composite
def garbage_run(draw: st.DrawFn) -> bytes:
    """Data bytes, undefined statuses, stray EOX, partial messages."""
    parts: list[bytes] = []
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.integers(0, 3))
        if kind == 0:
            parts.append(bytes(draw(st.lists(garbage_byte, min_size=1, max_size=8))))
        elif kind == 1:
            parts.append(b"\xf7")
        elif kind == 2:  # a message cut short (status + too few data bytes)
            status = draw(st.sampled_from([0x80, 0x90, 0xB0, 0xE0, 0xF2]))
            parts.append(bytes([status, *draw(st.lists(data7, max_size=1))]))
        else:  # an unterminated sysex
            parts.append(bytes([0xF0, *draw(st.lists(data7, max_size=6))]))
    return b"".join(parts)


@st.composite
def noisy_stream(draw: st.DrawFn) -> tuple[bytes, list[MidiMessage], int]:
    enc = Encoder(draw)
    garbage_total = 0
    after_garbage = False
    for _ in range(draw(st.integers(0, 40))):
        if draw(st.integers(0, 2)) == 0:
            g = draw(garbage_run())
            enc.add_raw(g)
            garbage_total += len(g)
            after_garbage = True
        else:
            spec = draw(valid_msg)
            enc.add(spec, force_status=after_garbage)
            # A real-time byte does not resync; keep forcing a status byte.
            if spec[0] < 0xF8:
                after_garbage = False
    # enc.messages() holds only the valid messages, in emission order.
    return bytes(enc.buf), enc.messages(), garbage_total


def is_subsequence(needle: list[MidiMessage], haystack: list[MidiMessage]) -> bool:
    it = iter(haystack)
    return all(any(m == h for h in it) for m in needle)


@given(noisy_stream(), st.data())
@settings(max_examples=400)
def test_property_garbage_never_hides_valid_messages(
    stream: tuple[bytes, list[MidiMessage], int], dd: st.DataObject
) -> None:
    data, must, garbage_total = stream
    msgs, stats = parse(data)
    assert is_subsequence(must, msgs)
    assert stats.garbage_bytes <= garbage_total
    assert stats.bytes_in == len(data)
    assert feed_in_chunks(data, split_points(dd, len(data))) == (msgs, stats)


@given(st.binary(max_size=400), st.integers(0, 64), st.data())
@settings(max_examples=300)
def test_property_arbitrary_bytes_never_raise(
    data: bytes, max_sysex: int, dd: st.DataObject
) -> None:
    msgs, stats = parse(data, max_sysex=max_sysex)
    assert parse_bytewise(data, max_sysex=max_sysex) == (msgs, stats)
    cuts = split_points(dd, len(data))
    assert feed_in_chunks(data, cuts, max_sysex=max_sysex) == (msgs, stats)
    assert stats.bytes_in == len(data)
    assert stats.messages == len(msgs)
    for m in msgs:
        assert m.kind != "unknown"
        assert all(b < 0x80 for b in m.data)
        assert 0 <= m.offset < len(data)
        if m.status == 0xF0:
            assert len(m.data) <= max_sysex
    # offsets of non-real-time messages are strictly increasing
    offs = [m.offset for m in msgs if m.status < 0xF8]
    assert offs == sorted(set(offs))


@given(st.binary(max_size=400), st.integers(0, 64))
@settings(max_examples=300)
def test_property_every_byte_accounted_for(data: bytes, max_sysex: int) -> None:
    # A trailing tune request flushes whatever is pending (it interrupts a
    # partial message, ends an open SysEx) so the accounting is exact.
    stream = data + b"\xf6"
    msgs, stats = parse(stream, max_sysex=max_sysex)
    assert msgs[-1] == M(0xF6, b"", len(data))
    used = 0
    sysex = 0
    for m in msgs:
        if m.status == 0xF0:
            sysex += 1
            used += 1 + len(m.data)  # F0 + payload; F7 counted below
        else:
            explicit = stream[m.offset] >= 0x80
            used += len(m.data) + explicit
    eox = sysex - stats.sysex_truncated
    assert used + eox + stats.garbage_bytes == len(stream)
    assert stats.running_status_used == sum(1 for m in msgs if stream[m.offset] < 0x80)


@given(st.lists(st.one_of(channel_msg(), common_msg(), sysex_msg, realtime_msg), max_size=60))
@settings(max_examples=300)
def test_property_matches_mido_without_running_status(specs: list[Spec]) -> None:
    data = bytearray()
    for status, payload in specs:
        data += bytes([status, *payload, 0xF7]) if status == 0xF0 else bytes([status, *payload])
    ours = [m.to_mido(as_sent=True) for m in MidiStreamParser().feed(bytes(data))]
    parser = mido.Parser()
    parser.feed(bytes(data))
    theirs = list(parser)
    assert ours == theirs
    # default to_mido() normalises vel-0 note-ons to note-offs
    normalised = [
        mido.Message("note_off", channel=m.channel, note=m.note, velocity=0)
        if m.type == "note_on" and m.velocity == 0
        else m
        for m in theirs
    ]
    assert [m.to_mido() for m in MidiStreamParser().feed(bytes(data))] == normalised


def test_mido_tokenizer_drops_running_status() -> None:
    """Documents why this module exists."""
    data = bytes([0x99, 38, 100, 40, 90])
    parser = mido.Parser()
    parser.feed(data)
    assert len(list(parser)) == 1
    assert len(MidiStreamParser().feed(data)) == 2


def test_stats_is_dataclass_tuple() -> None:
    _, stats = parse(bytes([0x90, 60, 100, 61, 100, 5, 0xF4]))
    assert astuple(stats) == (7, 2, 2, 0, 0, 1)  # 5 interrupted, F4
