"""MIDI port source: an ALSA or JACK MIDI input through python-rtmidi, polled, driver-stamped.

No Python in the driver's thread. rtmidi reads the device on a thread of its own (JACK's
process callback, or RtMidi's ALSA sequencer thread). A Python callback there must take the
daemon's interpreter lock: on a loaded machine that delays the stamp by milliseconds and,
inside JACK's process cycle, can make the server drop events. So no callback is installed:
the driver thread only pushes each message into rtmidi's own lock-free queue (C++, bounded
by :data:`QUEUE_LIMIT`), and the daemon's thread drains it with ``get_message`` every
:data:`POLL_S` (0.5 ms) while waiting for input. Nothing in the driver thread waits for us.

Stamps from the driver. Each queued message carries the time since the previous one,
measured in the driver thread (JACK: ``jack_get_time()`` in the process callback; ALSA: the
sequencer's real-time event stamp, taken by the kernel on arrival).
:class:`~livedrummer.midi.drivertime.DeltaStamper` anchors their running sum on the shared clock,
so a note's time no longer depends on when the daemon got the CPU. rtmidi's JACK backend
loses the delta of a message it filters out, so the driver is told to filter nothing and
system messages (SysEx, clock, active sensing) are dropped here, after their delta counts.

Port choice. By exact name, else by a unique case-insensitive substring ("TD-17" finds
"TD-17:TD-17 MIDI 1 20:0"). ``api="auto"`` looks on every MIDI system rtmidi was built with
and takes the one the port is on (ALSA first when both have it: a JACK port of the same name
is normally a bridge to the ALSA device, one more hop); :attr:`MidiPortSource.api_used`
says which, and the daemon logs it.

Reconnect. rtmidi does not report a vanished device, so ``read`` polls the port list every
:data:`PROBE_S` and raises :class:`MidiInputError` when the port is gone; the daemon reopens
it when it comes back (every ``reconnect_s``, 0.1 s by default). While the port is absent,
``open`` looks for it through clients kept for the whole outage (one per MIDI system), so a
retry costs a port listing, not a new MIDI client (registering a JACK client each time would
churn the server's graph ten times a second). A port that vanishes and comes back between
two probes is not noticed (rtmidi gives no connection state), hence the short probe interval.

Limits. rtmidi's queue drops what does not fit, silently (it writes a line on stderr): at
:data:`QUEUE_LIMIT` messages that is over 6 s of a 10,000 notes/s flood with the daemon not
reading at all. Polling costs the daemon about 2,000 short wake-ups a second (a few per cent
of one core) and adds up to :data:`POLL_S` to the time from arrival to publication, not to
the stamp. JACK's stamp is the time the process callback ran in the cycle the note came in
(within one period, 2.7 ms at 128 frames / 48 kHz, of the sender's write), and that thread
is itself late when the CPU is; realtime scheduling (``jackd -R``, the rig's default) and
``-S`` keep it on time: see the JACK settings in docs/guide/rig.md.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

import rtmidi

from livedrummer.errors import MidiInputError
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.drivertime import DeltaStamper
from livedrummer.native.stderr import native_stderr_to_log
from livedrummer.timeline.clock import Clock

from .base import Event, MidiSource, Problems

log = logging.getLogger("livedrummer.input")

PROBE_S = 0.1
POLL_S = 0.0005
QUEUE_LIMIT = 65_536
#: At most this many messages per ``read``, so a flood is published in batches as it comes.
MAX_BATCH = 256
#: The MIDI systems by the name options use; ``auto`` is all of them, in this order.
APIS = {"alsa": rtmidi.API_LINUX_ALSA, "jack": rtmidi.API_UNIX_JACK}
API_CHOICES = ("auto", *APIS)


def _api_names(api: str) -> list[str]:
    if api == "auto":
        compiled = set(rtmidi.get_compiled_api())
        return [name for name, code in APIS.items() if code in compiled]
    if api not in APIS:
        raise MidiInputError(f"MIDI API {api!r}: expected one of {', '.join(API_CHOICES)}")
    return [api]


def midi_in(api: str, client: str = "livedrummer") -> Any:
    """A MidiIn client of one named MIDI system ("alsa" or "jack")."""
    if api not in APIS:
        raise MidiInputError(f"MIDI API {api!r}: expected one of {', '.join(APIS)}")
    try:
        with native_stderr_to_log(log, f"MIDI API {api}"):  # libasound/libjack noise: ours only
            return rtmidi.MidiIn(APIS[api], client, queue_size_limit=QUEUE_LIMIT)
    except (rtmidi.RtMidiError, RuntimeError) as exc:
        raise MidiInputError(f"MIDI API {api}: cannot start a client ({exc})") from None


def list_ports(api: str = "auto") -> list[str]:
    """Input port names of ``api`` (all systems for "auto"; MidiInputError when none runs)."""
    return [port for _, port in list_ports_by_api(api)]


def list_ports_by_api(api: str = "auto") -> list[tuple[str, str]]:
    """(system, port name) of every input port; MidiInputError when no asked system runs."""
    found: list[tuple[str, str]] = []
    problems: list[str] = []
    names = _api_names(api)
    for name in names:
        try:
            m = midi_in(name, "livedrummer-ports")
        except MidiInputError as exc:
            problems.append(str(exc))
            continue
        try:
            found += [(name, str(p)) for p in m.get_ports()]
        finally:
            m.delete()
    if len(problems) == len(names):
        raise MidiInputError("; ".join(problems) or f"MIDI API {api}: none compiled in")
    return found


def choose_port(spec: str, ports: list[str]) -> int:
    if spec in ports:
        return ports.index(spec)
    hits = [i for i, p in enumerate(ports) if spec.lower() in p.lower()]
    if len(hits) == 1:
        return hits[0]
    listed = ", ".join(repr(p) for p in ports) or "none"
    problem = "matches several ports" if hits else "not found"
    raise MidiInputError(f"MIDI port {spec!r}: {problem} (available: {listed})")


class MidiPortSource(MidiSource):
    def __init__(
        self,
        spec: str,
        clock: Clock,
        decoder: MessageDecoder,
        api: str = "auto",
        problems: Problems | None = None,
        *,
        virtual: bool = False,
        thru: Callable[[list[int]], None] | None = None,
    ) -> None:
        super().__init__(f"{'virtual' if virtual else 'midi'}:{spec}", clock, decoder, problems)
        self.spec = spec
        self.api = api
        self.virtual = virtual
        self.thru = thru  # every message read, forwarded before it is decoded (input --thru)
        self.api_used = ""
        self.port_name = ""
        self.stamper = DeltaStamper()
        self._in: Any = None
        self._clients: dict[str, Any] = {}  # kept across retries while the port is absent
        self._next_probe = 0.0
        _api_names(api)  # a bad name fails here, not at the first retry

    def check(self) -> None:
        """The port is there now (or, virtual, a MIDI system to open it on); else one line."""
        if self.virtual:
            self._virtual_client().delete()
            return
        names = [name for _, name in list_ports_by_api(self.api)]
        try:
            choose_port(self.spec, names)
        except MidiInputError as exc:
            raise MidiInputError(f"{exc}; --wait waits for it") from None

    def _virtual_client(self) -> Any:
        problems: list[str] = []
        for name in _api_names(self.api):
            try:
                m = midi_in(name)
            except MidiInputError as exc:
                problems.append(str(exc))
                continue
            self.api_used = name
            return m
        raise MidiInputError(f"{self.name}: {'; '.join(problems) or 'no MIDI system'}")

    def _open_virtual(self) -> None:
        m = self._virtual_client()
        try:
            m.ignore_types(sysex=False, timing=False, active_sense=False)
            m.open_virtual_port(self.spec)
        except rtmidi.RtMidiError as exc:
            m.delete()
            raise MidiInputError(f"{self.name}: {exc}") from exc
        self._in = m
        self.port_name = self.spec
        log.warning(
            "%s: virtual input port %r open on %s", self.name, self.spec, self.api_used.upper()
        )
        self.stamper.reset()
        self._next_probe = float("inf")  # our own port: it cannot disappear
        self.is_open = True

    def open(self) -> None:
        if self.virtual:
            self._open_virtual()
            return
        ports: list[tuple[str, str, int]] = []  # (system, name, index on that system)
        problems: list[str] = []
        for name in _api_names(self.api):
            try:
                m = self._clients.get(name) or midi_in(name)
                self._clients[name] = m
                ports += [(name, str(p), i) for i, p in enumerate(m.get_ports())]
            except (MidiInputError, rtmidi.RtMidiError) as exc:
                problems.append(str(exc))
        if not ports and problems:
            self._drop_clients()
            raise MidiInputError(f"{self.name}: {'; '.join(problems)}")
        # The same name on two systems: the first system (ALSA) wins (see the docstring).
        seen: dict[str, tuple[str, int]] = {}
        for system, port, index in ports:
            seen.setdefault(port, (system, index))
        names = list(seen)
        port_name = names[choose_port(self.spec, names)]
        system, index = seen[port_name]
        m = self._clients.pop(system)
        try:
            m.ignore_types(sysex=False, timing=False, active_sense=False)  # deltas: docstring
            m.open_port(index, "in")
        except rtmidi.RtMidiError as exc:
            m.delete()
            self._drop_clients()
            raise MidiInputError(f"{self.name}: {exc}") from exc
        self._drop_clients()  # the other systems' clients are not needed while open
        self._in = m
        self.port_name = port_name
        if self.api_used != system:
            log.warning(
                "%s: port %r on %s (--api %s)", self.name, self.port_name, system.upper(), self.api
            )
        self.api_used = system
        self.stamper.reset()
        self._next_probe = self.clock.now() + PROBE_S
        self.is_open = True

    def read(self, timeout_s: float) -> list[Event]:
        out: list[Event] = []
        now = self.clock.now
        deadline = now() + timeout_s
        get = self._in.get_message
        stamp = self.stamper.stamp
        taken = 0
        while taken < MAX_BATCH:
            item = get()
            if item is None:
                if out or now() >= deadline:
                    break
                time.sleep(POLL_S)
                continue
            taken += 1
            msg, delta_s = item
            if self.thru is not None:
                self.thru(msg)
            t = stamp(delta_s, now())
            if msg and msg[0] < 0xF0:  # channel messages only; system ones gave their delta
                self.decode(t, msg[0], msg[1:], out)
        t = now()
        if t >= self._next_probe and not self.virtual:
            self._next_probe = t + PROBE_S
            try:
                present = self.port_name in [str(p) for p in self._in.get_ports()]
            except rtmidi.RtMidiError:
                present = False
            if not present:
                raise MidiInputError(f"{self.name}: port {self.port_name!r} disappeared")
        return out

    def close(self) -> None:
        if self._in is not None:
            try:
                self._in.close_port()
            finally:
                self._in.delete()
                self._in = None
        self._drop_clients()
        self.is_open = False

    def _drop_clients(self) -> None:
        for m in self._clients.values():
            m.delete()
        self._clients.clear()
