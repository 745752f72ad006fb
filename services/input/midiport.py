"""MIDI port source: an ALSA or JACK MIDI input through python-rtmidi.

The port is chosen by exact name, else by a unique case-insensitive substring ("TD-17"
finds "TD-17:TD-17 MIDI 1 20:0"). rtmidi calls back on its own thread; the callback stamps
the shared clock first, then queues the bytes, so queueing delay never shifts a timestamp.
rtmidi does not report a vanished device, so ``read`` polls the port list every
:data:`PROBE_S` and raises :class:`MidiInputError` when the port is gone; the daemon reopens
it when it comes back (it retries every ``reconnect_s``, 0.1 s by default). While the port is
absent, ``open`` looks for it through one client kept for the whole outage, so a retry costs
a port listing, not a new MIDI client (registering a JACK client each time would churn the
server's graph ten times a second). A port that vanishes and comes back between two probes
is not noticed (rtmidi gives no connection state), hence the short probe interval. The queue
is bounded (:data:`MAX_QUEUE`): beyond it messages are shed and counted, and the daemon
publishes a GAP.

rtmidi is used directly rather than through mido's port wrapper to get the callback
timestamp and the port list from one object without a second thread.

JACK caveat, measured here: a JACK2 server in its default *asynchronous* mode does not wait
for a late client, and on a CPU-starved machine (no realtime priority, cores busy) the MIDI a
late client reads is lost or is the previous cycle's again (3,000 notes at 1,000/s with one
busy Python thread beside the reader: 1,438 received, nearly all wrong). With ``jackd -S``
(synchronous) or realtime scheduling the same run is exact (3,000 of 3,000). Stage rigs and
the tests run jackd with ``-S``.
"""

from __future__ import annotations

import queue
from typing import Any

import rtmidi

from livedrummer.clock import Clock
from livedrummer.decode import MessageDecoder
from livedrummer.errors import MidiInputError
from livedrummer.protocol import Gap, GapReason
from services.input.base import Event, MidiSource, Problems

PROBE_S = 0.1
MAX_QUEUE = 200_000
APIS = {
    "alsa": rtmidi.API_LINUX_ALSA,
    "jack": rtmidi.API_UNIX_JACK,
    "default": rtmidi.API_UNSPECIFIED,
}


def midi_in(api: str, client: str = "livedrummer") -> Any:
    """A MidiIn client of ``api``; "default" tries each compiled API (ALSA, then JACK)."""
    if api not in APIS:
        raise MidiInputError(f"MIDI API {api!r}: expected one of {', '.join(APIS)}")
    tries = rtmidi.get_compiled_api() if api == "default" else [APIS[api]]
    problems = []
    for rtapi in tries:
        try:
            return rtmidi.MidiIn(rtapi, client)
        except rtmidi.RtMidiError as exc:
            problems.append(f"{rtmidi.get_api_name(rtapi)}: {exc}")
    raise MidiInputError(f"MIDI API {api}: cannot start a client ({'; '.join(problems)})")


def list_ports(api: str = "default") -> list[str]:
    """Input port names of ``api`` (raises MidiInputError when the MIDI system is absent)."""
    m = midi_in(api, "livedrummer-ports")
    try:
        return [str(p) for p in m.get_ports()]
    finally:
        m.delete()


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
        api: str = "default",
        problems: Problems | None = None,
    ) -> None:
        super().__init__(f"midi:{spec}", clock, decoder, problems)
        self.spec = spec
        self.api = api
        self.port_name = ""
        self._in: Any = None
        self._client: Any = None  # the rtmidi client, kept across retries while absent
        self._queue: queue.SimpleQueue[tuple[float, list[int]]] = queue.SimpleQueue()
        self._shed = 0
        self._shed_first = 0.0
        self._next_probe = 0.0

    def open(self) -> None:
        if self._client is None:
            self._client = midi_in(self.api)  # kept while the port is absent (docstring)
        m = self._client
        try:
            ports = [str(p) for p in m.get_ports()]
            index = choose_port(self.spec, ports)
            m.ignore_types(sysex=True, timing=True, active_sense=True)
            m.set_callback(self._callback)
            m.open_port(index, "in")
        except rtmidi.RtMidiError as exc:
            self._drop_client()
            raise MidiInputError(f"{self.name}: {exc}") from exc
        self._in = m
        self.port_name = ports[index]
        self._next_probe = self.clock.now() + PROBE_S
        self.is_open = True

    def _callback(self, event: tuple[list[int], float], _data: object) -> None:
        t = self.clock.now()
        if self._queue.qsize() >= MAX_QUEUE:
            if not self._shed:
                self._shed_first = t
            self._shed += 1
            return
        self._queue.put((t, event[0]))

    def read(self, timeout_s: float) -> list[Event]:
        out: list[Event] = []
        try:
            item = self._queue.get(timeout=timeout_s)
        except queue.Empty:
            item = None
        while item is not None:
            t, msg = item
            if msg:
                self.decode(t, msg[0], msg[1:], out)
            try:
                item = self._queue.get_nowait()
            except queue.Empty:
                item = None
        if self._shed:
            out.append(Gap(self._shed, self._shed_first, self.clock.now(), GapReason.QUEUE_FULL))
            self.problems.report("queue full", f"{self.name}: shed messages", self._shed)
            self._shed = 0
        now = self.clock.now()
        if now >= self._next_probe:
            self._next_probe = now + PROBE_S
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
                self._in.cancel_callback()
                self._in.close_port()
            finally:
                self._in = None
        self._drop_client()
        self.is_open = False

    def _drop_client(self) -> None:
        if self._client is not None:
            self._client.delete()
            self._client = None
