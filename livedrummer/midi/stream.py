"""Incremental MIDI 1.0 byte-stream parser for DIY trigger boards.

Many home-made e-drum trigger boards (Arduino, RP2040, Teensy ...) do not
enumerate as a USB-MIDI device; they simply write raw MIDI 1.0 bytes to a USB
serial port at 31,250 or 115,200 baud.  This module turns such a byte stream,
delivered in arbitrary chunks by serial reads, into :class:`MidiMessage`
objects.  It is pure logic: no I/O, no logging, no threads.

Why not ``mido``?  mido's byte tokenizer ignores *running status*: a data byte
that arrives without a preceding status byte is dropped.  On a serial link
running status is the norm rather than the exception, because a sender that
omits repeated status bytes saves a third of the bandwidth on note traffic
(at 31,250 baud a 3-byte note takes ~1 ms, a 2-byte one ~0.64 ms), and a
drum roll is exactly a long run of note-ons on one channel.  Dropping those
bytes loses hits.

Rules implemented (MIDI 1.0 specification):

* **Running status** applies to channel voice messages only.  A status byte
  0x80-0xEF sets it; a System Common byte 0xF0-0xF7 (including SysEx, EOX
  and the undefined 0xF4/0xF5) clears it; System Real-Time bytes 0xF8-0xFF
  leave it untouched.
* **System Real-Time** bytes (0xF8-0xFF) may appear anywhere, even between
  the data bytes of another message or inside a SysEx.  They are emitted at
  once as their own message and the interrupted message simply continues.
  The undefined real-time bytes 0xF9 and 0xFD are counted as garbage and
  otherwise ignored (they do not interrupt anything either).
* **SysEx** (0xF0 ... 0xF7) payloads are collected up to ``max_sysex``
  payload bytes (F0/F7 excluded; default 4096).  A longer SysEx is discarded
  entirely: all of its bytes, including the F0 and a terminating F7, are
  counted as garbage and ``sysex_too_long`` is incremented.  A SysEx ended by
  any non-real-time status byte other than F7 is *truncated*: as the spec
  says, that status byte implies the end of the SysEx, so it is emitted with
  the payload received so far and ``sysex_truncated`` is incremented.
  :attr:`MidiMessage.data` of a SysEx holds the payload only, like mido.
* **System Common** lengths: 0xF1 and 0xF3 take one data byte, 0xF2 two,
  0xF6 none.  0xF4 and 0xF5 are undefined and count as garbage.
* **Note-on with velocity 0** is reported as a note-off (status 0x8n, data
  ``(note, 0)``) with :attr:`MidiMessage.note_on_vel0` set to ``True``.

What counts as garbage (:attr:`ParserStats.garbage_bytes`):

* data bytes with no message to belong to (no running status, e.g. after a
  System Common message or at the very start of the stream),
* the partial bytes of a message interrupted by a new non-real-time status
  byte (the explicit status byte, if one was sent, plus any data bytes),
* undefined status bytes (0xF4, 0xF5, 0xF9, 0xFD) and an EOX (0xF7) that
  does not end a SysEx,
* every byte of a SysEx that exceeded ``max_sysex``.

The parser never raises on any input and always resynchronises at the next
status byte.  Feeding a stream in any chunking yields exactly the same
messages (with the same offsets) as feeding it in one piece; a message split
across chunks is emitted by the ``feed`` call that delivers its last byte.

Limits: a message that is still incomplete when the stream stops is simply
held until more bytes arrive (there is no timeout; a caller that wants one can
call :meth:`MidiStreamParser.reset`).  Offsets are byte offsets since the
parser was created or last reset; for a running-status message the offset is
that of its first data byte.  A corrupted data byte that is still < 0x80
cannot be detected -- MIDI 1.0 has no checksums.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["MidiMessage", "MidiStreamParser", "ParserStats"]


# --------------------------------------------------------------------------
# Tables
# --------------------------------------------------------------------------

_CHANNEL_KINDS = {
    0x80: "note_off",
    0x90: "note_on",
    0xA0: "polytouch",
    0xB0: "control_change",
    0xC0: "program_change",
    0xD0: "aftertouch",
    0xE0: "pitchwheel",
}

_SYSTEM_KINDS = {
    0xF0: "sysex",
    0xF1: "quarter_frame",
    0xF2: "songpos",
    0xF3: "song_select",
    0xF6: "tune_request",
    0xF8: "clock",
    0xFA: "start",
    0xFB: "continue",
    0xFC: "stop",
    0xFE: "active_sensing",
    0xFF: "reset",
}


def _kind_for(status: int) -> str:
    if 0x80 <= status < 0xF0:
        return _CHANNEL_KINDS[status & 0xF0]
    return _SYSTEM_KINDS.get(status, "unknown")


#: ``_KIND[status]`` -> message kind name ("unknown" for data/undefined bytes).
_KIND: tuple[str, ...] = tuple(_kind_for(s) for s in range(256))

#: Number of data bytes following a status byte (channel + system common).
#: 0 for statuses that do not start a data-carrying message.
_DATA_LEN: tuple[int, ...] = tuple(
    (1 if (s & 0xF0) in (0xC0, 0xD0) else 2)
    if 0x80 <= s < 0xF0
    else {0xF1: 1, 0xF2: 2, 0xF3: 1}.get(s, 0)
    for s in range(256)
)

#: Pre-built ``data`` objects so the hot loop never allocates them.
_D1: tuple[bytes, ...] = tuple(bytes((i,)) for i in range(128))
_D2: tuple[bytes, ...] = tuple(bytes((i >> 7, i & 0x7F)) for i in range(128 * 128))
_EMPTY = b""

_REALTIME_UNDEFINED = (0xF9, 0xFD)


# --------------------------------------------------------------------------
# Data types
# --------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class MidiMessage:
    """One parsed MIDI message.

    ``status`` is the full status byte (including the channel for channel
    voice messages).  ``data`` holds the data bytes (for SysEx: the payload
    without F0/F7).  ``offset`` is the stream offset of the message's first
    byte -- the status byte, or the first data byte when running status was
    used.  ``note_on_vel0`` is ``True`` when this note-off was actually sent
    as a note-on with velocity 0.
    """

    status: int
    data: bytes
    offset: int
    note_on_vel0: bool = False

    @property
    def kind(self) -> str:
        """mido-style type name, e.g. ``"note_on"`` (``"unknown"`` if undefined)."""
        return _KIND[self.status & 0xFF]

    @property
    def channel(self) -> int | None:
        """Channel 0-15 for channel voice messages, else ``None``."""
        s = self.status
        return s & 0x0F if 0x80 <= s < 0xF0 else None

    @property
    def note(self) -> int | None:
        """Note number for note_on/note_off/polytouch, else ``None``."""
        if 0x80 <= self.status < 0xB0:
            return self.data[0]
        return None

    @property
    def velocity(self) -> int | None:
        """Velocity for note_on/note_off, else ``None``."""
        if 0x80 <= self.status < 0xA0:
            return self.data[1]
        return None

    @property
    def control(self) -> int | None:
        """Controller number for control_change, else ``None``."""
        if 0xB0 <= self.status < 0xC0:
            return self.data[0]
        return None

    @property
    def value(self) -> int | None:
        """The message's main value, else ``None``.

        * polytouch, control_change: second data byte,
        * program_change (program), aftertouch (pressure), song_select,
          quarter_frame: the single data byte,
        * pitchwheel: signed bend -8192..8191 (mido's ``pitch``),
        * songpos: 14-bit position in MIDI beats.
        """
        s = self.status
        hi = s & 0xF0
        d = self.data
        if hi in (0xA0, 0xB0):
            return d[1]
        if hi in (0xC0, 0xD0) or s in (0xF1, 0xF3):
            return d[0]
        if hi == 0xE0:
            return (d[0] | (d[1] << 7)) - 8192
        if s == 0xF2:
            return d[0] | (d[1] << 7)
        return None

    def to_bytes(self) -> bytes:
        """Wire encoding with an explicit status byte (SysEx incl. F0/F7)."""
        if self.status == 0xF0:
            return b"\xf0" + self.data + b"\xf7"
        return bytes((self.status,)) + self.data

    def to_mido(self, *, as_sent: bool = False) -> Any:
        """Return the equivalent ``mido.Message``.

        A note-on with velocity 0 becomes ``note_off`` with velocity 0, unless
        ``as_sent`` is true, in which case it is returned as the ``note_on``
        velocity 0 it was sent as.
        """
        import mido

        raw = self.to_bytes()
        if as_sent and self.note_on_vel0:
            raw = bytes((0x90 | (self.status & 0x0F),)) + self.data
        return mido.Message.from_bytes(raw)


@dataclass(slots=True)
class ParserStats:
    """Running counters of a :class:`MidiStreamParser`."""

    bytes_in: int = 0
    #: Messages emitted (real-time and truncated SysEx included).
    messages: int = 0
    garbage_bytes: int = 0
    #: SysEx ended by a status byte other than F7 (still emitted).
    sysex_truncated: int = 0
    #: SysEx longer than ``max_sysex`` (discarded, bytes counted as garbage).
    sysex_too_long: int = 0
    #: Messages whose status byte was omitted (running status).
    running_status_used: int = 0


# --------------------------------------------------------------------------
# Parser
# --------------------------------------------------------------------------


class MidiStreamParser:
    """Incremental MIDI 1.0 parser; see the module docstring for the rules."""

    __slots__ = (
        "_cur",
        "_d0",
        "_explicit",
        "_got",
        "_moff",
        "_offset",
        "_running",
        "_sx_buf",
        "_sx_discard",
        "_sx_off",
        "_sysex",
        "max_sysex",
        "stats",
    )

    def __init__(self, max_sysex: int = 4096) -> None:
        if max_sysex < 0:
            raise ValueError("max_sysex must be >= 0")
        self.max_sysex = max_sysex
        self.stats = ParserStats()
        self._init_state()

    def _init_state(self) -> None:
        self._offset = 0  # stream offset of the next byte
        self._running = 0  # channel running status, 0 = none
        self._cur = 0  # status of the message being assembled (or running)
        self._explicit = False  # current message had an explicit status byte
        self._got = 0  # data bytes collected for the current message (0/1)
        self._d0 = 0  # first data byte of a two-byte message
        self._moff = 0  # offset of the current message
        self._sysex = False  # inside a SysEx
        self._sx_discard = False  # inside a too-long SysEx being discarded
        self._sx_buf = bytearray()
        self._sx_off = 0

    def reset(self) -> None:
        """Forget all state: partial messages, running status, offsets, stats."""
        self.stats = ParserStats()
        self._init_state()

    def feed(self, chunk: bytes | bytearray | memoryview) -> list[MidiMessage]:
        """Parse ``chunk`` and return the messages it completes, in order."""
        out: list[MidiMessage] = []
        append = out.append
        msg = MidiMessage
        d1 = _D1
        d2 = _D2
        dlen = _DATA_LEN

        off = self._offset
        running = self._running
        cur = self._cur
        explicit = self._explicit
        got = self._got
        d0 = self._d0
        moff = self._moff
        sysex = self._sysex
        sx_discard = self._sx_discard
        sx_buf = self._sx_buf
        sx_off = self._sx_off
        max_sysex = self.max_sysex
        need = dlen[cur]

        garbage = 0
        truncated = 0
        too_long = 0
        rs_used = 0

        for b in chunk:
            if b < 0x80:
                # ---------------- data byte ----------------
                if got:
                    # Second data byte of a two-byte message: complete.
                    got = 0
                    if not explicit:
                        rs_used += 1
                    explicit = False
                    if b == 0 and cur & 0xF0 == 0x90:
                        append(msg(cur - 0x10, d2[d0 << 7], moff, True))
                    else:
                        append(msg(cur, d2[(d0 << 7) | b], moff))
                    cur = running
                    need = dlen[cur]
                elif need:
                    if not explicit:
                        moff = off
                    if need == 2:
                        d0 = b
                        got = 1
                    else:
                        if not explicit:
                            rs_used += 1
                        explicit = False
                        append(msg(cur, d1[b], moff))
                        cur = running
                        need = dlen[cur]
                elif sysex:
                    if sx_discard:
                        garbage += 1
                    elif len(sx_buf) < max_sysex:
                        sx_buf.append(b)
                    else:
                        # Too long: discard F0 + payload so far + this byte.
                        garbage += len(sx_buf) + 2
                        sx_buf.clear()
                        sx_discard = True
                else:
                    garbage += 1
            elif b >= 0xF8:
                # ---------------- system real-time ----------------
                if b == 0xF9 or b == 0xFD:
                    garbage += 1
                else:
                    append(msg(b, _EMPTY, off))
            else:
                # ---------------- status byte 0x80-0xF7 ----------------
                if sysex:
                    sysex = False
                    if sx_discard:
                        sx_discard = False
                        too_long += 1
                        if b == 0xF7:
                            garbage += 1
                    else:
                        if b != 0xF7:
                            truncated += 1
                        append(msg(0xF0, bytes(sx_buf), sx_off))
                        sx_buf.clear()
                    if b == 0xF7:
                        off += 1
                        continue
                elif explicit or got:
                    # A partial message is interrupted.
                    garbage += got + explicit
                    got = 0

                if b < 0xF0:
                    running = cur = b
                    need = dlen[b]
                    explicit = True
                    moff = off
                else:
                    running = cur = 0
                    explicit = False
                    need = dlen[b]
                    if need:
                        cur = b
                        explicit = True
                        moff = off
                    elif b == 0xF0:
                        sysex = True
                        sx_off = off
                    elif b == 0xF6:
                        append(msg(b, _EMPTY, off))
                    else:
                        # 0xF4, 0xF5, or an EOX outside a SysEx.
                        garbage += 1
            off += 1

        self._offset = off
        self._running = running
        self._cur = cur
        self._explicit = explicit
        self._got = got
        self._d0 = d0
        self._moff = moff
        self._sysex = sysex
        self._sx_discard = sx_discard
        self._sx_off = sx_off

        st = self.stats
        st.bytes_in += len(chunk)
        st.messages += len(out)
        st.garbage_bytes += garbage
        st.sysex_truncated += truncated
        st.sysex_too_long += too_long
        st.running_status_used += rs_used
        return out
