"""The live window's drum keys: each key played goes out as a MIDI note into the input daemon.

In a live show (``display --live``, ``up``) a key of :mod:`livedrummer.midi.keypads` must
reach the pipeline as a real stroke. The route chosen is MIDI: :class:`KeySender` is a MIDI
output (python-rtmidi, JACK or ALSA) connected to the virtual input port the input daemon
opened (``input --virtual NAME``; ``up --keys`` opens ``livedrummer-keys`` and points the
window at it). A key is then exactly what a kit's pad would be: the input daemon stamps it,
reads it through its note map, journals it (so ``sessions`` and replays hold the keys
played) and publishes the onset, and the synth moves the drummer's arms to it. Sending an
onset straight to the synth would skip the journal and the map, and need a second publisher
the synth does not listen to. The notes are General MIDI drum notes on channel 10, so the
input should read them with the ``general-midi`` map (``up --keys`` does).

Limits: the port is found by name (a substring, as ``--midi`` does) when the first key is
played and looked for again on later keys until it is there (the input may open it after the
window); until then keys are dropped with one warning. Each key sends a note-on and, at
once, its note-off (drum pads do the same; the duration means nothing to a drum).
"""

from __future__ import annotations

import logging
from typing import Any

log = logging.getLogger(__name__)

KEYS_PORT = "livedrummer-keys"  #: the virtual port ``up --keys`` opens for the window's keys
CHANNEL = 9  #: General MIDI's drum channel (10, counted from 1)


class KeySender:
    """A MIDI output to the input port named ``port`` (see the module docstring)."""

    def __init__(self, port: str, api: str = "auto") -> None:
        self.port = port
        self.api = api
        self.sent = 0
        self.dropped = 0
        self._out: Any = None
        self._warned = False

    def _connect(self) -> bool:
        import rtmidi

        apis = {"jack": rtmidi.API_UNIX_JACK, "alsa": rtmidi.API_LINUX_ALSA}
        wanted = list(apis) if self.api == "auto" else [self.api]
        compiled = set(rtmidi.get_compiled_api())
        for name in wanted:
            if apis[name] not in compiled:
                continue
            try:
                out = rtmidi.MidiOut(apis[name], "livedrummer-window")
            except (rtmidi.RtMidiError, RuntimeError):
                continue
            ports = out.get_ports()
            hits = [i for i, p in enumerate(ports) if self.port in p]
            if hits:
                out.open_port(hits[0], "keys")
                self._out = out
                log.info("keys: playing into %r (%s)", ports[hits[0]], name.upper())
                return True
            out.delete()
        return False

    def send(self, note: int, velocity: int) -> bool:
        """Play ``note`` at ``velocity``; False (dropped) while the port is not there."""
        if self._out is None and not self._connect():
            self.dropped += 1
            if not self._warned:
                log.warning(
                    "keys: no MIDI input port %r to play into (is `input --virtual "
                    "%s` running?); keys are dropped until it is there",
                    self.port,
                    self.port,
                )
                self._warned = True
            return False
        self._out.send_message([0x90 | CHANNEL, note, velocity])
        self._out.send_message([0x80 | CHANNEL, note, 0])
        self.sent += 1
        log.info("keys: note %d velocity %d", note, velocity)
        return True

    def close(self) -> None:
        if self._out is not None:
            self._out.close_port()
            self._out.delete()
            self._out = None
