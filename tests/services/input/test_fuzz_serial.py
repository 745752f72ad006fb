"""A megabyte of noise with valid messages in it: the parser, then the serial daemon on a pty.

The stream comes from :func:`services.bench._fuzz.noisy_serial_stream` (see its docstring for why
every inserted message must come out intact: each carries its own status byte, and the only
bytes inside one are real-time bytes, which interrupt nothing). Garbage may add messages, so
the inserted ones are checked as a subsequence of the output, with their offsets.
"""

from __future__ import annotations

import os
import random
import threading
from pathlib import Path

import numpy as np
import pytest
import zmq
from test_input import ROLAND, Subscriber, assert_contiguous, pty_pair, start_daemon

from livedrummer import protocol as p
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.stream import MidiMessage, MidiStreamParser
from livedrummer.timeline.clock import MonotonicClock
from services.bench._fuzz import REALTIME, Inserted, SerialStream, noisy_serial_stream
from services.input.serialport import SerialSource

SEED = 20240607
NOTES = (36, 38, 42, 46, 49)  # all in the roland-td map


@pytest.fixture(scope="module")
def stream() -> SerialStream:
    return noisy_serial_stream(random.Random(SEED), 1_000_000, notes=NOTES)


def expected(m: Inserted) -> MidiMessage:
    if m.status & 0xF0 == 0x90 and m.data[1] == 0:  # not generated, but the rule holds
        return MidiMessage(m.status - 0x10, m.data, m.offset, note_on_vel0=True)
    return MidiMessage(m.status, m.data, m.offset)


def missing_from(needle: list[MidiMessage], haystack: list[MidiMessage]) -> list[MidiMessage]:
    """The needles not found, in order, as a subsequence of ``haystack``."""
    it = iter(haystack)
    return [m for m in needle if not any(m == h for h in it)]


def test_every_inserted_message_survives_a_megabyte_of_noise(stream: SerialStream) -> None:
    rng = random.Random(SEED + 1)
    # A trailing tune request flushes whatever is pending, so the byte accounting is exact.
    data = stream.data + b"\xf6"
    parser = MidiStreamParser()
    msgs: list[MidiMessage] = []
    pos = 0
    chunks = 0
    while pos < len(data):
        size = rng.choice((1, 2, 3, rng.randint(1, 64), rng.randint(1, 4096)))
        msgs.extend(parser.feed(data[pos : pos + size]))
        pos += size
        chunks += 1
    stats = parser.stats
    assert chunks > 1000 and stats.bytes_in == len(data)
    assert len(stream.inserted) > 20_000 and stream.realtime_inside > 1000

    must = [expected(m) for m in stream.inserted]
    assert missing_from(must, msgs) == []
    # Each real-time byte put inside an inserted message came out on its own, at its offset
    # (the undefined 0xF9 and 0xFD are ignored and counted as garbage).
    realtime_at = {m.offset: m.status for m in msgs if m.status >= 0xF8}
    inside = 0
    for ins in stream.inserted:
        pos, left = ins.offset + 1, len(ins.data)
        while left:
            b = data[pos]
            if b >= 0xF8:
                inside += 1
                assert realtime_at.get(pos) == (None if b in (0xF9, 0xFD) else b)
            else:
                left -= 1
            pos += 1
    assert inside == stream.realtime_inside

    # Garbage was seen, counted, and only garbage was counted as such.
    assert 0 < stats.garbage_bytes <= stream.garbage_bytes
    assert stats.sysex_too_long > 0 and stats.sysex_truncated > 0
    assert stats.messages == len(msgs) > len(must)
    # Every byte is accounted for: in a message, an EOX ending a SysEx, or garbage.
    used = 0
    sysex = 0
    for m in msgs:
        if m.status == 0xF0:
            sysex += 1
            used += 1 + len(m.data)
        else:
            used += len(m.data) + (data[m.offset] >= 0x80)
    eox = sysex - stats.sysex_truncated
    assert used + eox + stats.garbage_bytes == len(data)
    assert stats.running_status_used == sum(1 for m in msgs if data[m.offset] < 0x80)
    assert set(realtime_at.values()) <= set(REALTIME)


def test_the_same_stream_through_a_pty_into_the_serial_daemon(
    stream: SerialStream, tmp_path: Path
) -> None:
    """Every inserted note-on is published as an onset, in order, through a real pty."""
    note_ons = [m for m in stream.inserted if m.status & 0xF0 == 0x90]
    assert len(note_ons) > 3000
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    master, name = pty_pair()
    clock = MonotonicClock()
    src = SerialSource(name, clock, MessageDecoder(ROLAND, 0), baud=1_000_000)
    daemon, thread, stop = start_daemon(src, clock, ctx, tmp_path, wait_subscribers=1)
    data = stream.data

    def write_all() -> None:
        for k in range(0, len(data), 4096):
            os.write(master, data[k : k + 4096])

    try:
        sub = Subscriber(ctx, daemon.endpoints["pub"])
        sub.sock.setsockopt(zmq.RCVHWM, 0)
        sub.collect(lambda s: src.is_open, 10)
        writer = threading.Thread(target=write_all, daemon=True)
        writer.start()
        # Bounded: stop once the parser has seen every byte and the bus is quiet.
        sub.collect(lambda s: src.parser.stats.bytes_in >= len(data), 25)
        writer.join(5)
        sub.collect(lambda s: False, 0.5)
    finally:
        stop.set()
        thread.join(10)
        os.close(master)
        ctx.destroy(linger=0)
    assert not writer.is_alive()
    assert src.parser.stats.bytes_in == len(data)
    got = sub.rows(p.Kind.ONSET)
    pairs = list(zip(got["note"].tolist(), got["velocity"].tolist(), strict=True))
    it = iter(pairs)
    lost = [m for m in note_ons if not any((m.data[0], m.data[1]) == x for x in it)]
    assert lost == []
    assert len(pairs) >= len(note_ons)  # garbage may add notes, never remove them
    assert (np.diff(got["time_s"]) > 0).all()
    assert_contiguous(sub)
    garbage = src.parser.stats.garbage_bytes
    assert garbage > 0 and daemon.problems.counts["serial garbage"] == garbage
