"""The MIDI port source against a real JACK server (``jackd -d dummy``: no sound card).

A virtual rtmidi output port plays the kit; the daemon opens it by name through the JACK API,
publishes, and reconnects when the port is removed and created again. Skipped, with the
reason, where jackd is not installed or cannot start (Debian package jackd2).
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.clock import MonotonicClock
from services.input.daemon import DaemonConfig, InputDaemon
from services.input.midiport import MidiPortSource, list_ports, list_ports_by_api

rtmidi = pytest.importorskip("rtmidi")


def kit_port() -> Any:
    out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "kit")
    out.open_virtual_port("pads")
    return out


def test_daemon_receives_notes_from_a_jack_port_and_reconnects(
    jack_server: str, tmp_path: Path
) -> None:
    kit = kit_port()
    assert "kit:pads" in list_ports("jack")
    listed = subprocess.run(
        [sys.executable, "-m", "services", "ports", "--api", "jack"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    assert ": kit:pads  [jack]" in listed
    assert ("jack", "kit:pads") in list_ports_by_api("auto")  # ALSA absent or not: JACK found
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    clock = MonotonicClock()
    source = MidiPortSource(
        "pads", clock, MessageDecoder(load_note_map("roland-td"), 3), api="auto"
    )
    config = DaemonConfig(
        pub="tcp://127.0.0.1:*",
        control="tcp://127.0.0.1:*",
        performer=3,
        sessions_dir=tmp_path,
        reconnect_s=0.05,
    )
    daemon = InputDaemon(source, config, clock, ctx)
    daemon.start()
    stop = threading.Event()
    thread = threading.Thread(target=daemon.run, args=(stop,), daemon=True)
    thread.start()
    sub = ctx.socket(zmq.SUB)
    sub.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
    sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.GAP))
    sub.connect(daemon.endpoints["pub"])
    received: list[p.Message] = []

    def onsets() -> list[int]:
        return [int(n) for m in received if m.kind is p.Kind.ONSET for n in m.rows["note"]]

    def collect(until: Any, timeout_s: float = 10.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not until() and time.monotonic() < deadline:
            if sub.poll(20):
                received.append(p.decode(sub.recv_multipart()))

    try:
        # The subscription and the JACK connection settle asynchronously: probe until a note lands.
        sent_at: list[float] = []
        deadline = time.monotonic() + 10
        while not onsets() and time.monotonic() < deadline:
            kit.send_message([0x99, 36, 100])
            collect(lambda: bool(onsets()), 0.1)
        assert onsets(), "no note reached the daemon through JACK"
        assert source.api_used == "jack"  # --api auto took the system the port is on
        received.clear()
        notes = [38, 42, 46, 36, 49, 51] * 20
        for i, note in enumerate(notes):
            sent_at.append(clock.now())
            kit.send_message([0x99, note, 1 + i % 127])
            time.sleep(0.002)  # a drummer at 500 notes/s, not a handshake
        collect(lambda: len(onsets()) >= len(notes))
        assert onsets() == notes
        stamps = [float(t) for m in received if m.kind is p.Kind.ONSET for t in m.rows["time_s"]]
        assert all(s >= t for s, t in zip(stamps, sent_at, strict=True))  # stamped after sending

        kit.close_port()  # the kit is unplugged ...
        del kit
        collect(lambda: not source.is_open, 5)
        assert not source.is_open and daemon.problems.counts["source lost"] == 1
        kit = kit_port()  # ... and plugged in again
        collect(lambda: any(m.kind is p.Kind.GAP for m in received), 5)
        assert source.is_open
        received.clear()
        deadline = time.monotonic() + 5
        while not onsets() and time.monotonic() < deadline:
            kit.send_message([0x99, 38, 77])
            collect(lambda: bool(onsets()), 0.1)
        assert onsets() and set(onsets()) == {38}
    finally:
        stop.set()
        thread.join(5)
        sub.close(0)
        ctx.term()


def test_an_unknown_midi_api_is_one_clear_error() -> None:
    from livedrummer.errors import MidiInputError

    with pytest.raises(MidiInputError, match="'coremidi': expected one of auto, alsa, jack"):
        MidiPortSource(
            "pads", MonotonicClock(), MessageDecoder(load_note_map("roland-td")), api="coremidi"
        )
