"""Repairing the track events that other readers accept and mido refuses.

mido parses a track strictly. Files that other readers (and synthesizers) play hold a few
mistakes that cost nothing to read past:

* a meta event of the wrong length for its type (a 2-byte time signature: mido fails with "list
  index out of range") or with values out of range (a key signature of 9 sharps);
* running status right after a SysEx event. The SMF specification says SysEx cancels running
  status; rhythm-game charts rely on it continuing, and mido then reads the data byte as a
  SysEx length ("data byte must be in range 0..127").

:func:`repair_track` rewrites one track chunk's events into an equivalent track mido reads:
a malformed meta event becomes a text event of the same delta time (times are kept exactly;
meta events carry no drum data), and a running-status event after SysEx gets its status byte
written out. Each kind of repair is reported once per track, naming the byte offset in the file
of its first occurrence and how many there were. What cannot be read past (a channel event with a
data byte of 128 or more, a status byte no file may hold, an event that runs past its track)
raises :class:`~livedrummer.errors.MidiFileError` naming the track and the byte.

Only files mido refuses come here (the reader tries mido first), so the byte loop in Python
costs nothing on sound files.
"""

from __future__ import annotations

from livedrummer.errors import MidiFileError

#: Meta event types with one fixed length, as mido's meta specs (and the SMF spec) have them.
META_LENGTHS = {0x00: 2, 0x20: 1, 0x21: 1, 0x2F: 0, 0x51: 3, 0x54: 5, 0x58: 4, 0x59: 2}
_META_NAMES = {0x00: "sequence number", 0x20: "channel prefix", 0x21: "MIDI port",
               0x2F: "end of track", 0x51: "tempo", 0x54: "SMPTE offset",
               0x58: "time signature", 0x59: "key signature"}  # fmt: skip
_TEXT = 0x01


def _varlen(data: bytes, pos: int, end: int) -> tuple[int, int]:
    value = 0
    for i in range(4):
        if pos >= end:
            raise EOFError
        byte = data[pos]
        pos += 1
        value = (value << 7) | (byte & 0x7F)
        if byte < 0x80:
            return value, pos
        if i == 3:
            raise ValueError("a variable-length number longer than 4 bytes")
    raise AssertionError("unreachable")  # pragma: no cover


def _encode_varlen(value: int) -> bytes:
    out = [value & 0x7F]
    value >>= 7
    while value:
        out.append(0x80 | (value & 0x7F))
        value >>= 7
    return bytes(reversed(out))


def _meta_fault(kind: int, payload: bytes) -> str | None:
    """Why mido would refuse this meta event, or None."""
    want = META_LENGTHS.get(kind)
    if want is not None and len(payload) != want and not (kind == 0x00 and not payload):
        return f"{_META_NAMES[kind]} meta event of {len(payload)} bytes (expected {want})"
    if kind == 0x59 and (not -7 <= (payload[0] ^ 0x80) - 0x80 <= 7 or payload[1] > 1):
        return f"key signature meta event with values {payload[0]}, {payload[1]}"
    return None


def repair_track(
    data: bytes, start: int, end: int, name: str, where: str
) -> tuple[bytes, list[str]]:
    """The events of ``data[start:end]`` (one track's body) rewritten for mido, and warnings.

    ``name`` is the file's in errors; ``where`` names the track in errors and warnings
    (``"track 2 (bytes 100-2000)"``).
    """
    out = bytearray()
    found: dict[str, tuple[int, int]] = {}  # problem -> (first byte offset, count)
    running: int | None = None  # the last channel status byte
    after_sysex = False
    pos = start
    at = f"{name}: {where}"

    def note(problem: str, at: int) -> None:
        first, n = found.get(problem, (at, 0))
        found[problem] = (first, n + 1)

    try:
        while pos < end:
            event = pos
            delta, pos = _varlen(data, pos, end)
            if pos >= end:
                raise EOFError
            status = data[pos]
            if status == 0xFF:
                if pos + 1 >= end:
                    raise EOFError
                kind = data[pos + 1]
                length, body = _varlen(data, pos + 2, end)
                if body + length > end:
                    raise EOFError
                payload = data[body : body + length]
                fault = _meta_fault(kind, payload)
                if fault is not None:
                    note(f"{fault} read as text", pos)
                    kind = _TEXT
                out += _encode_varlen(delta) + bytes((0xFF, kind))
                out += _encode_varlen(length) + payload
                pos = body + length
                if kind == 0x2F:
                    break
                continue
            if status in (0xF0, 0xF7):
                length, body = _varlen(data, pos + 1, end)
                if body + length > end:
                    raise EOFError
                out += data[event : body + length]
                pos = body + length
                after_sysex = True
                continue
            if status >= 0xF0:
                raise MidiFileError(
                    f"{name}: {where}: byte {pos}: status 0x{status:02X} is not a file event"
                )
            if status < 0x80:
                if running is None:
                    raise MidiFileError(
                        f"{at}: byte {pos}: running status with no status before it"
                    )
                if after_sysex:
                    note("running status after a SysEx event", pos)
                first_data = pos
            else:
                running = status
                first_data = pos + 1
            size = 1 if running & 0xF0 in (0xC0, 0xD0) else 2
            if first_data + size > end:
                raise EOFError
            for i in range(first_data, first_data + size):
                if data[i] >= 0x80:
                    raise MidiFileError(
                        f"{at}: byte {i}: data byte 0x{data[i]:02X} is not in range 0..127"
                    )
            out += _encode_varlen(delta) + bytes((running,)) + data[first_data : first_data + size]
            pos = first_data + size
            after_sysex = False
    except EOFError:
        raise MidiFileError(
            f"{at}: byte {event}: an event runs past the end of its track"
        ) from None
    except ValueError as exc:
        raise MidiFileError(f"{at}: byte {event}: {exc}") from None
    warnings = [
        f"{where}: byte {first}: {problem}" + (f" ({n} times)" if n > 1 else "")
        for problem, (first, n) in found.items()
    ]
    return bytes(out), warnings
