"""MIDI thru: what the kit sends, forwarded as it is read to another MIDI port (a DAW, a
sampler), optionally re-mapped (:mod:`livedrummer.midi.thrumap`).

``PORT`` names an existing MIDI input port (exact name or unique substring, as ``--midi``
does) to connect to; where none matches, a virtual output port of that name is opened for a
DAW to connect to. The input daemon's thread calls :meth:`MidiThru.send` for every message
the moment it takes it from rtmidi's queue, before decoding it, so the thru adds the poll
interval (0.5 ms) and a Python call to what the kit's own latency is; ``bench`` figures are in
docs/guide/sound.md. A send that fails (the port went away) is counted and logged once; the daemon
carries on.
"""

from __future__ import annotations

import logging
from typing import Any

import rtmidi

from livedrummer.errors import MidiInputError
from livedrummer.midi.thrumap import Remap
from livedrummer.native.stderr import native_stderr_to_log

from .midiport import APIS, _api_names, choose_port

log = logging.getLogger("livedrummer.input")


class MidiThru:
    """See the module docstring."""

    def __init__(
        self, spec: str, api: str = "auto", remap: Remap | None = None, what: str = "thru"
    ) -> None:
        self.spec = spec
        self.what = what
        self.remap = remap
        self.sent = 0
        self.failed = 0
        self.port_name = ""
        self._out: Any = None
        problems: list[str] = []
        for name in _api_names(api):
            try:
                with native_stderr_to_log(log, f"MIDI API {name}"):  # libasound/libjack: logged
                    out = rtmidi.MidiOut(APIS[name], f"livedrummer-{what}")
            except (rtmidi.RtMidiError, RuntimeError) as exc:
                problems.append(f"{name}: {exc}")
                continue
            ports = [str(p) for p in out.get_ports()]
            try:
                index = choose_port(spec, ports)
            except MidiInputError:
                index = -1
            try:
                if index >= 0:
                    out.open_port(index, "thru")
                    self.port_name = ports[index]
                else:
                    out.open_virtual_port(spec)
                    self.port_name = spec
            except rtmidi.RtMidiError as exc:
                out.delete()
                problems.append(f"{name}: {exc}")
                continue
            self._out = out
            log.warning(
                "%s: sending to %s port %r on %s%s",
                what,
                "the" if index >= 0 else "a virtual",
                self.port_name,
                name.upper(),
                " (re-mapped)" if remap is not None else "",
            )
            return
        raise MidiInputError(f"--{what} {spec}: {'; '.join(problems) or 'no MIDI system'}")

    def send(self, msg: list[int]) -> None:
        try:
            self._out.send_message(self.remap(msg) if self.remap is not None else msg)
            self.sent += 1
        except (rtmidi.RtMidiError, ValueError) as exc:
            self.failed += 1
            if self.failed == 1:
                log.warning("%s: cannot send to %r: %s", self.what, self.port_name, exc)

    def close(self) -> None:
        if self._out is not None:
            self._out.close_port()
            self._out.delete()
            self._out = None
