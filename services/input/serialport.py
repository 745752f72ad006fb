"""Serial source: raw MIDI bytes from a DIY trigger board over USB serial (pyserial).

Bytes go through :class:`~livedrummer.midi.stream.MidiStreamParser` (running status, real-time
bytes between data bytes, SysEx, garbage; see its docstring), then the shared decoder. Each
read returns whatever the driver holds (at least one byte, or nothing after ``timeout_s``),
and every message it completes is stamped with the time that read returned: serial drivers
deliver in chunks, so messages in one chunk share an arrival time (at 31,250 baud a 3-byte
note takes ~1 ms on the wire; that is the resolution a chunk can hide). Within a chunk they
are spaced :data:`CHUNK_SPACING_S` (1 µs) apart, ending at the read time: a serial line
cannot carry two messages at one instant, so two identical notes in one chunk are two hits,
never the same-instant duplicates the shared decoder drops from files. A chunk so big that
this spacing would reach back past the previous read's time is spaced closer, so stamps
always increase.

What bounds a serial stamp. A tty gives no kernel timestamp per byte, so the stamp is taken
in the daemon's own thread right after ``read`` returns: no callback, no queue, no other
thread's lock in between (the main thread is the only one that reads). Its error is what
held the bytes back before that read: the USB bridge (FTDI chips hold up to their latency
timer, 16 ms by default: set ``/sys/bus/usb-serial/devices/ttyUSB0/latency_timer`` to 1;
CDC-ACM boards deliver once per 1 ms USB frame), a real UART's receive FIFO (up to its
trigger level, then a timeout of about four characters: ~1.3 ms at 31,250 baud), and the
daemon's wait for the CPU, which ``input --realtime PRIO`` removes. The read takes what the
driver holds, so the read size adds nothing beyond the chunking above.

A device that vanishes (cable pulled: pyserial raises, or reads EOF) becomes a
:class:`MidiInputError`; the daemon reopens the path until it exists again. Garbage bytes
the parser skipped are counted in the problems report.
"""

from __future__ import annotations

import glob
import os
from typing import Any

import serial

from livedrummer.errors import MidiInputError
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.stream import MidiStreamParser
from livedrummer.timeline.clock import Clock

from .base import Event, MidiSource, Problems

#: Messages completed by one read are stamped this far apart (ending at the read time), in
#: order: identical hits in one chunk are two hits, and the decoder must not see them as a
#: file's same-instant "double events".
CHUNK_SPACING_S = 1e-6

BAUD_RATES = (31_250, 38_400, 57_600, 115_200, 230_400, 250_000, 500_000, 1_000_000)


def serial_devices() -> list[str]:
    """Serial devices a trigger board is likely on: USB serial, CDC-ACM, stable by-id names."""
    found: list[str] = []
    for pattern in ("/dev/serial/by-id/*", "/dev/ttyUSB*", "/dev/ttyACM*", "/dev/ttyAMA*"):
        found += sorted(glob.glob(pattern))
    return found


class SerialSource(MidiSource):
    def __init__(
        self,
        device: str,
        clock: Clock,
        decoder: MessageDecoder,
        baud: int = 31_250,
        problems: Problems | None = None,
    ) -> None:
        super().__init__(f"serial:{device}", clock, decoder, problems)
        self.device = device
        self.baud = baud
        self.parser = MidiStreamParser()
        self._port: Any = None
        self._garbage_seen = 0
        self._last_read_s = float("-inf")

    def check(self) -> None:
        if not os.path.exists(self.device):
            found = ", ".join(serial_devices()) or "none"
            raise MidiInputError(
                f"{self.name}: no such device (serial devices here: {found}; --wait waits for it)"
            )

    def open(self) -> None:
        try:
            self._port = serial.Serial(self.device, self.baud, timeout=0.05)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise MidiInputError(f"{self.name}: cannot open: {exc}") from exc
        self.parser.reset()
        self._garbage_seen = 0
        self._last_read_s = float("-inf")
        self.is_open = True

    def read(self, timeout_s: float) -> list[Event]:
        port = self._port
        try:
            if port.timeout != timeout_s:
                port.timeout = timeout_s
            data = port.read(max(1, port.in_waiting))
        except (serial.SerialException, OSError, TypeError) as exc:
            # pyserial raises TypeError from inside read when a pty's other end closes.
            raise MidiInputError(f"{self.name}: read failed: {exc}") from exc
        if not data:
            return []
        t = self.clock.now()
        out: list[Event] = []
        messages = [m for m in self.parser.feed(data) if m.status < 0xF0]
        last = len(messages) - 1
        # Closer spacing when a big chunk would reach back past the previous read's stamps.
        step = min(CHUNK_SPACING_S, (t - self._last_read_s) / (last + 1)) if messages else 0.0
        for i, msg in enumerate(messages):
            self.decode(t - (last - i) * step, msg.status, msg.data, out)
        self._last_read_s = t
        garbage = self.parser.stats.garbage_bytes
        if garbage > self._garbage_seen:
            new = garbage - self._garbage_seen
            self.problems.report("serial garbage", f"{self.name}: skipped {new} bytes", new)
            self._garbage_seen = garbage
        return out

    def close(self) -> None:
        if self._port is not None:
            try:
                self._port.close()
            except (serial.SerialException, OSError):
                pass
            self._port = None
        self.is_open = False
