"""Seeded hostile input: a noisy serial byte stream and mutated Standard MIDI Files.

The hardening tests (``tests/test_fuzz_*.py``) and ``livedrummer bench fuzz`` need the same
inputs, reproducible from a seed, so they are made here (in ``bench/``, beside the benchmark and
outside the installed package), as pure functions of a :class:`random.Random`.

**Serial stream** (:func:`noisy_serial_stream`). Runs of uniformly random bytes (every value:
status bytes, SysEx starts and ends, real-time and undefined bytes; now and then a SysEx too
long for a parser to keep) alternate with complete,
valid channel messages (note on/off, control change, polyphonic aftertouch, program change,
channel pressure, pitch bend). Every inserted message carries its own status byte, and some
have real-time bytes (0xF8-0xFF, the undefined 0xF9/0xFD included) between their bytes. That
makes "not corrupted" exact: a status byte ends whatever garbage left pending (a partial
message becomes garbage, an open SysEx is ended) and real-time bytes interrupt nothing, so
by MIDI 1.0 a correct parser must emit every inserted message, with its status, data and the
offset of its status byte. What garbage may legitimately add is *extra* messages: random
data bytes right after an inserted message complete messages under its running status, and
random status bytes start messages of their own. So the check is "the inserted messages are a
subsequence of the output", never equality.

**SMF mutations** (:func:`mutations`). Each variant of a valid file is a named case: cut at a
random offset, bits flipped, a run of random bytes written over it, a huge delta time
inserted, the tempo set to zero, a track length larger than the file, an enormous declared
track count, and, built from scratch, absurd note counts. A reader must return a bounded,
correct result or raise its named error for every one.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Iterator
from dataclasses import dataclass

__all__ = [
    "Inserted",
    "SerialStream",
    "Variant",
    "absurd_note_file",
    "mutations",
    "noisy_serial_stream",
]

#: Status nibbles of the channel messages inserted into the serial stream.
CHANNEL_KINDS = (0x80, 0x90, 0xA0, 0xB0, 0xC0, 0xD0, 0xE0)
#: Real-time bytes put inside inserted messages (the undefined 0xF9/0xFD included).
REALTIME = (0xF8, 0xF9, 0xFA, 0xFB, 0xFC, 0xFD, 0xFE, 0xFF)


@dataclass(frozen=True, slots=True)
class Inserted:
    """A valid message put into the noise: status, data, offset of its status byte."""

    status: int
    data: bytes
    offset: int


@dataclass(frozen=True, slots=True)
class SerialStream:
    """The noisy stream, what was inserted into it, and how many bytes were garbage runs."""

    data: bytes
    inserted: tuple[Inserted, ...]
    garbage_bytes: int  # bytes in the random runs (upper bound for the parser's garbage)
    realtime_inside: int  # real-time bytes placed between the bytes of inserted messages


def noisy_serial_stream(
    rng: random.Random,
    size: int = 1_000_000,
    *,
    notes: tuple[int, ...] = (36, 38, 42, 46, 49),
    max_run: int = 48,
) -> SerialStream:
    """About ``size`` bytes: random runs of 0..``max_run`` bytes between valid messages.

    Note-ons use ``notes`` (pick ones a note map knows to follow them through a decoder) and a
    velocity of 1..127 so each one is an onset; other kinds take any data.
    """
    out = bytearray()
    inserted: list[Inserted] = []
    garbage = 0
    realtime_inside = 0
    while len(out) < size:
        if rng.random() < 0.001:
            # Now and then a SysEx longer than a parser keeps (4096), ended or not by EOX.
            payload = bytes(b & 0x7F for b in rng.randbytes(rng.randint(4100, 6000)))
            run_bytes = b"\xf0" + payload + (b"\xf7" if rng.random() < 0.5 else b"")
        else:
            run_bytes = rng.randbytes(rng.randint(0, max_run))
        out += run_bytes
        garbage += len(run_bytes)
        hi = rng.choice(CHANNEL_KINDS)
        status = hi | rng.randrange(16)
        if hi == 0x90:
            data = bytes((rng.choice(notes), rng.randint(1, 127)))
        elif hi in (0xC0, 0xD0):
            data = bytes((rng.randrange(128),))
        else:
            data = bytes((rng.randrange(128), rng.randrange(128)))
        inserted.append(Inserted(status, data, len(out)))
        out.append(status)
        for b in data:
            if rng.random() < 0.1:
                out.append(rng.choice(REALTIME))
                realtime_inside += 1
            out.append(b)
    return SerialStream(bytes(out), tuple(inserted), garbage, realtime_inside)


# --------------------------------------------------------------------------------------------
# Standard MIDI Files
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Variant:
    """One mutated file: what was done to it, and its bytes."""

    kind: str
    detail: str
    data: bytes


def _track_chunks(data: bytes) -> list[tuple[int, int]]:
    """(offset of header, length) of each MTrk chunk of a valid file."""
    (hlen,) = struct.unpack(">I", data[4:8])
    pos = 8 + hlen
    chunks = []
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos + 4 : pos + 8])
        if data[pos : pos + 4] == b"MTrk":
            chunks.append((pos, length))
        pos += 8 + length
    return chunks


def _varlen(value: int) -> bytes:
    out = [value & 0x7F]
    value >>= 7
    while value:
        out.append(0x80 | (value & 0x7F))
        value >>= 7
    return bytes(reversed(out))


def _insert_into_track(data: bytes, track: int, at: int, event: bytes) -> bytes:
    """Insert ``event`` (delta + message) at byte ``at`` of a track body, fixing its length."""
    pos, length = _track_chunks(data)[track]
    body = data[pos + 8 : pos + 8 + length]
    body = body[:at] + event + body[at:]
    return data[:pos] + b"MTrk" + struct.pack(">I", len(body)) + body + data[pos + 8 + length :]


def absurd_note_file(count: int, *, delta: int = 0, tpb: int = 480) -> bytes:
    """One track of ``count`` note-ons (running status, ``delta`` ticks apart) and their ends."""
    body = bytearray(b"\x00\xff\x51\x03\x07\xa1\x20")  # 120 bpm
    body += b"\x00\x99\x26\x64"
    step = _varlen(delta) + b"\x26\x64"
    body += step * (count - 1)
    body += b"\x00\xff\x2f\x00"
    header = b"MThd" + struct.pack(">IHHH", 6, 0, 1, tpb)
    return header + b"MTrk" + struct.pack(">I", len(body)) + bytes(body)


def mutations(data: bytes, rng: random.Random, per_kind: int = 1) -> Iterator[Variant]:
    """``per_kind`` variants of each mutation of a valid SMF ``data`` (see the docstring)."""
    chunks = _track_chunks(data)
    for _ in range(per_kind):
        cut = rng.randrange(len(data))
        yield Variant("truncated", f"cut at byte {cut}", data[:cut])

        flipped = bytearray(data)
        flips = rng.randint(1, 50)
        for _ in range(flips):
            flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
        yield Variant("bit-flipped", f"{flips} bits", bytes(flipped))

        runs = bytearray(data)
        start = rng.randrange(len(runs))
        run = rng.randint(1, 64)
        runs[start : start + run] = rng.randbytes(min(run, len(runs) - start))
        yield Variant("random-run", f"{run} bytes at {start}", bytes(runs))

        track = rng.randrange(len(chunks))
        # At the body's start (always an event boundary): a delta of 0x0FFFFFFF, the largest
        # variable-length quantity, carried by a text meta event.
        huge = _varlen(0x0FFFFFFF) + b"\xff\x01\x01x"
        yield Variant(
            "huge-delta",
            f"0x0FFFFFFF ticks in track {track + 1}",
            _insert_into_track(data, track, 0, huge),
        )

        # 0x00FFFFFF ticks: hours of silence, yet within a reader's bounds at most divisions.
        long = _insert_into_track(data, track, 0, _varlen(0x00FFFFFF) + b"\xff\x01\x01x")
        yield Variant("long-delta", f"0x00FFFFFF ticks at the start of track {track + 1}", long)

        zero = _insert_into_track(data, track, 0, b"\x00\xff\x51\x03\x00\x00\x00")
        yield Variant("zero-tempo", f"tempo 0 in track {track + 1}", zero)

        pos, length = chunks[track]
        bigger = length + rng.randint(1, 1 << 30)
        long_track = data[: pos + 4] + struct.pack(">I", bigger) + data[pos + 8 :]
        yield Variant("track-too-long", f"track {track + 1} declares {bigger} bytes", long_track)

        many = data[:10] + struct.pack(">H", 0xFFFF) + data[12:]
        yield Variant("many-tracks", "header declares 65535 tracks", many)
