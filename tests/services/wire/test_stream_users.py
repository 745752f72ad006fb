"""Every subscriber reads its stream through the one receiver, and counts the same.

Two checks. By the source: no module of ``services`` but :mod:`services.wire.stream_rx` reads a
SUB socket (the others that call ``recv`` are named below with the socket they read, none
a SUB), nothing but the intake builds a sequence tracker, and each subscriber builds a
:class:`~services.wire.stream_rx.StreamReceiver` (or the displays' PoseStream on it). By running:
the same numbered stream (a gap, a duplicate, a reorder, two sender restarts, junk) is sent
over real loopback sockets to each of the five subscribers (synth, live display, stage
display, practice bus, remote source), each reads it by its own read path, and all report
the same counts.
"""

from __future__ import annotations

import ast
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.stage.formation import Placement
from livedrummer.timeline.clock import MonotonicClock
from services.wire.stream_rx import Counts, StreamReceiver

SERVICES = Path(__file__).resolve().parents[3] / "services"
LOCAL = "tcp://127.0.0.1:*"
PERFORMER = 3
Frames = list[bytes]

#: Modules that call recv/recv_multipart on a socket that is not a SUB: (module, receiver).
NOT_SUB = {
    ("wire/net.py", "sock"),  # request_ready's DEALER and serve_control's ROUTER
    ("relay/service.py", "xsub"),  # the relay forwards bytes it never decodes (XSUB ...
    ("relay/service.py", "xpub"),  # ... and the subscriptions coming up its XPUB)
    ("input/daemon.py", "pub"),  # subscriptions arriving on the daemon's XPUB
    ("input/remote.py", "self._probe"),  # the clock exchange's DEALER
    ("wire/stream_rx.py", "sock"),  # the receiver itself
    ("display/parallel.py", "conn"),  # render --jobs: a worker's frames over its own pipe
}
#: The subscribers, and the name each must use the receiver by.
USERS = {
    "synth/service.py": "StreamReceiver",
    "display/live.py": "PoseStream",
    "display/stage_live.py": "PoseStream",
    "display/pose_stream.py": "StreamReceiver",
    "display/live_sound.py": "StreamReceiver",
    "display/practice_view.py": "waiting",
    "practice/bus.py": "StreamReceiver",
    "input/remote.py": "StreamReceiver",
    "bench/flood.py": "StreamReceiver",  # the one bench that counts sequence numbers
}


def _modules(benches: bool = False) -> Iterator[tuple[str, ast.Module]]:
    """The services' modules; benches left out unless asked (they time the wire with their
    own blocking reads of a probe socket, so they are held only to the sequence rule)."""
    for path in sorted(SERVICES.rglob("*.py")):
        rel = path.relative_to(SERVICES).as_posix()
        if benches or not rel.startswith("bench/"):
            yield rel, ast.parse(path.read_text(), rel)


def test_no_module_but_the_receiver_reads_a_sub_socket() -> None:
    found: set[tuple[str, str]] = set()
    for rel, tree in _modules():
        for node in ast.walk(tree):
            # any use of the method, called or not (an alias would hide a call)
            if isinstance(node, ast.Attribute) and node.attr in ("recv", "recv_multipart"):
                found.add((rel, ast.unparse(node.value)))
    assert found <= NOT_SUB, sorted(found - NOT_SUB)
    assert ("wire/stream_rx.py", "sock") in found  # the check sees what it looks for


def test_sequence_numbers_are_observed_only_by_the_intake_and_every_user_uses_it() -> None:
    names: dict[str, set[str]] = {}
    for rel, tree in _modules(benches=True):
        names[rel] = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | {
            n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)
        }
        assert not names[rel] & {"SequenceTracker", "observe_message"}, rel
    for rel, name in USERS.items():
        assert name in names[rel], f"{rel} does not use {name}"


# ---------------------------------------------------------------- the same stream, five users


def _pose_frames(seq: int, send_s: float, fmt: p.PoseFormat) -> Frames:
    rows = np.zeros(2, fmt.dtype)
    rows["rotation"][..., 3] = 1.0
    rows["time_s"] = [0.0, 1 / 240]
    msg = p.Message(p.Kind.POSE, p.Pose(send_s, rows), PERFORMER, seq, send_s, p.Stream.POSES)
    return p.encode(msg, fmt)


def _beat_frames(seq: int, send_s: float) -> Frames:
    return p.encode(p.Message(p.Kind.HEARTBEAT, None, PERFORMER, seq, send_s))


def script(good: Callable[[int, float], Frames], t0: float) -> list[Frames]:
    """(seq, send time) with: a gap (3, 4), a reorder (3 after 5), a duplicate (5 again), a
    restart at 0, one seen late (at 4 with a fresh send time), and two bad messages."""
    seqs = [
        (0, 0),
        (1, 1),
        (2, 2),
        (5, 5),
        (3, 3),
        (5, 5),
        (6, 6),
        (0, 20),
        (1, 21),
        (2, 22),
        (1, 40),
        (2, 41),
    ]
    out = [good(seq, t0 + k * 0.01) for seq, k in seqs]
    out.insert(7, [p.MAGIC + b"\x02" * 9])  # junk after the magic
    out.insert(3, p.encode(p.Message(p.Kind.HELLO, p.Hello("x", "y"), PERFORMER, 3)))
    return out


EXPECTED = Counts(received=10, missing=2, duplicates=2, restarts=2, bad=2)


@pytest.fixture
def ctx() -> Iterator[zmq.Context[zmq.Socket[bytes]]]:
    c: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    yield c
    c.destroy(linger=0)


def _user(
    name: str, ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str
) -> tuple[Callable[[], object], StreamReceiver, Callable[[], None], bool]:
    """(read once by the user's own path, its receiver, close, reads poses)."""
    kit = load_kit("rock5")
    if name == "synth":
        from services.synth.service import SynthConfig, SynthService

        synth = LiveSynth(build_rig(kit), SynthParams(0.01, 0.03))
        svc = SynthService(
            synth, SynthConfig(sub=endpoint, pub=LOCAL, control=LOCAL), MonotonicClock(), ctx
        )
        svc.start()
        return svc._drain, svc.rx, svc.shutdown, False
    if name == "display":
        from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock

        d = LiveDisplay(kit, LiveConfig(sub=endpoint, render=False), MonotonicFrameClock(), ctx)
        d.start()
        return d._drain, d.stream.rx, d.shutdown, True
    if name == "stage":
        from services.display.live import MonotonicFrameClock
        from services.display.stage_live import StageConfig, StageDisplay, StagePerformer

        who = [StagePerformer("a", PERFORMER, endpoint, kit, Placement(0.0, 0.0, 0.0))]
        s = StageDisplay(who, StageConfig(render=False), MonotonicFrameClock(), ctx)
        s.start()
        return s._drain, s.streams[0].rx, s.shutdown, True
    if name == "bus":
        from services.practice.bus import OnsetBus

        bus = OnsetBus(ctx, endpoint)
        return lambda: bus.read(0.01), bus.rx, bus.close, False
    from services.input.remote import RemoteSource

    src = RemoteSource(endpoint, MonotonicClock(), ctx)
    src.open()
    return lambda: src.read(0.01), src.rx, src.close, False


@pytest.mark.parametrize("name", ["synth", "display", "stage", "bus", "remote"])
def test_every_user_counts_the_same_stream_the_same(
    name: str, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    xpub = ctx.socket(zmq.XPUB)
    xpub.setsockopt(zmq.LINGER, 0)
    endpoint = f"tcp://127.0.0.1:{xpub.bind_to_random_port('tcp://127.0.0.1')}"
    read, rx, close, poses = _user(name, ctx, endpoint)
    try:
        assert xpub.poll(5000), f"{name} never subscribed"
        xpub.recv()
        fmt = p.PoseFormat.from_dtype(pose_dtype(len(load_kit("rock5").pieces)))
        good = (lambda s, t: _pose_frames(s, t, fmt)) if poses else _beat_frames
        frames = script(good, time.monotonic())
        for f in frames:
            xpub.send_multipart(f)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            read()
            c = rx.counts
            if c.received + c.duplicates + c.bad >= len(frames):
                break
        assert rx.counts == EXPECTED, name
    finally:
        close()
        xpub.close(0)
