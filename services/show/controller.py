"""A MIDI control surface steering the show: ``up --control FILE --control-midi PORT``.

Why this shape. A :class:`~livedrummer.live.controlmap.ControlMap` turns each controller or
pad message into the OSC command a cue desk would send; :class:`ControllerBridge` reads the
controller's port (:class:`~services.input.midiport.MidiPortSource`, the same code that reads
a kit) on a thread of its own and sends those commands as OSC datagrams to ``up``'s OSC port
on loopback (:class:`~services.show.osc.LoopbackSender`, which ``up``'s router forwards with too),
so a fader, a cue desk and a cue list all reach the synth and the display by the
one route of :mod:`services.show.osc`.

Limits: the controller must be there when ``up`` starts (it is checked then, one line naming
the ports that exist); a controller unplugged mid-show stops steering (the show goes on).
"""

from __future__ import annotations

import logging
import threading

from livedrummer.live.controlmap import ControlMap
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.clock import MonotonicClock

from ..input.base import RawMidi
from ..input.midiport import MidiPortSource
from .osc import LoopbackSender

log = logging.getLogger("livedrummer.up")


class ControllerBridge:
    """The controller's port read on a thread; its messages sent as OSC to ``osc_port``."""

    def __init__(self, port: str, mapping: ControlMap, osc_port: int, api: str = "auto") -> None:
        self.mapping = mapping
        self.osc_port = osc_port
        decoder = MessageDecoder(load_note_map("general-midi"))  # unused: only the tap is read
        self.source = MidiPortSource(port, MonotonicClock(), decoder, api=api)
        self.source.check()
        self.source.tap = self._heard
        self._out = LoopbackSender()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="up-controller", daemon=True)

    @property
    def sent(self) -> int:
        """OSC commands sent to ``up``'s port."""
        return self._out.sent

    def start(self) -> ControllerBridge:
        self.source.open()
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(2.0)
        self.source.close()
        self._out.close()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self.source.read(0.05)
        except Exception as exc:  # a controller that vanished: the show goes on without it
            log.warning("up: the MIDI controller stopped: %s", exc)

    def _heard(self, _time_s: float, msg: RawMidi) -> None:
        if msg.type == "control_change":
            cmds = self.mapping.commands("cc", msg.channel, msg.control, msg.value)
        elif msg.type in ("note_on", "note_off"):
            velocity = msg.velocity if msg.type == "note_on" else 0
            cmds = self.mapping.commands("note", msg.channel, msg.note, velocity)
        else:
            return
        for address, args in cmds:
            self._out.send(self.osc_port, address, args)
