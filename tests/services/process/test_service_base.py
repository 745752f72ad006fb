"""The service base: one start-up, READY handshake, control socket and shutdown for all three.

Real sockets on loopback. Each service (input daemon, synth, live display) is started, asked
HELLO on its control socket, and stopped; a start that fails half way (an endpoint already
taken) leaves nothing bound behind, so the same endpoints can be used at once by the next
start; and the process wrapper ``serve`` prints the endpoints line and stops on SIGTERM.
"""

from __future__ import annotations

import json
import signal
import socket as pysocket
import subprocess
import sys
import threading
from collections.abc import Iterator

import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.body.rig import build_rig
from livedrummer.errors import ProtocolError
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.timeline.clock import MonotonicClock
from services.cli.files import DEMO_MAP, demo_groove
from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock
from services.input.daemon import DaemonConfig, InputDaemon
from services.input.fileplayer import FileSource
from services.process.service import Service
from services.synth.service import SynthConfig, SynthService
from services.wire.net import request_ready

LOCAL = "tcp://127.0.0.1:*"


@pytest.fixture
def ctx() -> Iterator[zmq.Context[zmq.Socket[bytes]]]:
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    yield context
    context.term()


def free_port() -> int:
    with pysocket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def synth_service(ctx: zmq.Context[zmq.Socket[bytes]], pub: str, control: str) -> SynthService:
    synth = LiveSynth(build_rig(load_kit("rock5")), SynthParams(0.01, 0.03))
    return SynthService(
        synth, SynthConfig(sub="tcp://127.0.0.1:1", pub=pub, control=control), MonotonicClock(), ctx
    )


def services(ctx: zmq.Context[zmq.Socket[bytes]]) -> list[Service]:
    from livedrummer.midi.notemap import load_note_map

    clock = MonotonicClock()
    source = FileSource(demo_groove(), clock, load_note_map(DEMO_MAP), 0)
    source.load()
    daemon = InputDaemon(source, DaemonConfig(pub=LOCAL, control=LOCAL, journal=False), clock, ctx)
    display = LiveDisplay(
        load_kit("rock5"),
        LiveConfig(sub="tcp://127.0.0.1:1", render=False, control=LOCAL),
        MonotonicFrameClock(),
        ctx,
    )
    return [daemon, synth_service(ctx, LOCAL, LOCAL), display]


def test_every_service_answers_hello_with_its_ready_and_shuts_down_once(
    ctx: zmq.Context[zmq.Socket[bytes]],
) -> None:
    seen = {}
    for service in services(ctx):
        endpoints = service.start()
        try:
            answer = request_ready(ctx, endpoints["control"], p.Hello("test", "probe"), 5.0)
        finally:
            service.shutdown()
            service.shutdown()  # a second call does nothing
        seen[answer.service] = answer
        assert answer.endpoints == endpoints
        with pytest.raises(ProtocolError, match="no READY"):
            request_ready(ctx, endpoints["control"], p.Hello("test", "probe"), 0.3)
    assert set(seen) == {"input", "synth", "display"}
    assert seen["synth"].pose is not None and seen["synth"].pose == seen["display"].pose
    assert seen["input"].role == "source" and seen["display"].role == "frames"


def test_a_display_binds_no_control_socket_unless_asked(
    ctx: zmq.Context[zmq.Socket[bytes]],
) -> None:
    display = LiveDisplay(
        load_kit("rock5"),
        LiveConfig(sub="tcp://127.0.0.1:1", render=False),
        MonotonicFrameClock(),
        ctx,
    )
    assert "control" not in display.start()
    display.shutdown()


def test_a_start_that_fails_half_way_leaves_nothing_bound(
    ctx: zmq.Context[zmq.Socket[bytes]],
) -> None:
    control = f"tcp://127.0.0.1:{free_port()}"
    blocker = ctx.socket(zmq.PUB)
    blocker.setsockopt(zmq.LINGER, 0)
    taken = f"tcp://127.0.0.1:{free_port()}"
    blocker.bind(taken)
    try:
        failing = synth_service(ctx, taken, control)  # control binds, then the pub fails
        with pytest.raises(ProtocolError, match="cannot bind"):
            failing.start()
    finally:
        blocker.close(0)
    again = synth_service(ctx, taken, control)  # both endpoints are free again
    endpoints = again.start()
    try:
        assert endpoints["control"] == control and endpoints["pub"] == taken
        assert request_ready(ctx, control, p.Hello("test", "probe"), 5.0).service == "synth"
    finally:
        again.shutdown()


def test_serve_prints_the_endpoints_and_stops_on_sigterm() -> None:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "synth",
            "--sub",
            "tcp://127.0.0.1:1",
            "--pub",
            LOCAL,
            "--control",
            LOCAL,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = json.loads(proc.stdout.readline())
        assert line["service"] == "synth" and line["pub"].startswith("tcp://127.0.0.1:")
        ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        try:
            ready = request_ready(ctx, line["control"], p.Hello("test", "probe"), 10.0)
        finally:
            ctx.term()
        assert ready.endpoints["pub"] == line["pub"]
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "synth: 0 onsets" in err


def test_shutdown_from_another_thread_while_running_returns(
    ctx: zmq.Context[zmq.Socket[bytes]],
) -> None:
    service = synth_service(ctx, LOCAL, LOCAL)
    service.start()
    stop = threading.Event()
    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(service.run(stop)), daemon=True)
    thread.start()
    stop.set()
    thread.join(10)
    assert result == [0] and not thread.is_alive()
