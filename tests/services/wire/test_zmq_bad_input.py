"""Bad ZeroMQ input against every service that decodes network messages, on real sockets.

Each service runs in-process on loopback TCP: the synth (event SUB and control ROUTER), the
live display (pose SUB, rendering off), the input daemon (control ROUTER) and the remote
source (SUB). The test plays the peer: an XPUB that sees the service's subscription arrive
(so no message is sent before anyone listens), or a DEALER on a control socket. It sends one
message of each bad kind (wrong version byte, truncated header, random bytes, a body whose
size disagrees with the header, multi-frame garbage, a message above the payload limit, an
invalid payload, a valid message of a kind the socket does not serve) interleaved with good
ones, and checks that every good message was served, that the per-kind counters equal what
was sent, and that each kind was logged exactly once (further ones are only counted).

On a SUB socket, frames that do not start with the protocol magic never reach the service
(ZeroMQ's subscription filter drops them); the test sends some and checks they are not
counted, while the same random bytes on a control ROUTER are.
"""

from __future__ import annotations

import logging
import random
import struct
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import MonotonicClock
from services.cli.files import DEMO_MAP, demo_groove
from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock
from services.input.daemon import DaemonConfig, InputDaemon
from services.input.fileplayer import FileSource
from services.input.remote import RemoteSource
from services.synth.service import SynthConfig, SynthService
from services.wire.badmsg import BadMessages, kind_of

LOCAL = "tcp://127.0.0.1:*"
Frames = list[bytes]


@pytest.fixture
def ctx() -> Iterator[zmq.Context[zmq.Socket[bytes]]]:
    c: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    yield c
    c.destroy(linger=0)


# ---------------------------------------------------------------- bad frames, one table


def patch(head: bytes, fmt: str, offset: int, value: object) -> bytes:
    out = bytearray(head)
    struct.pack_into(fmt, out, offset, value)
    return bytes(out)


def onset_rows(n: int = 1, note: int = 38) -> np.ndarray:
    rows = np.zeros(n, p.SPECS[p.Kind.ONSET].rows)
    rows["note"], rows["velocity"], rows["openness"], rows["instrument"] = note, 90, np.nan, 1
    return rows


def bad_messages(good: Frames, rng: np.random.Generator) -> list[tuple[str, Frames]]:
    """(expected kind, frames) for every kind of bad message, built from a good message."""
    head, *payload = good
    big = p.MAX_PAYLOAD + 1
    return [
        ("version", [patch(head, "<B", 4, p.PROTOCOL_VERSION + 1), *payload]),
        ("version", [patch(head, "<B", 4, 0), *payload]),
        ("header", [head[:20], *payload]),  # truncated header
        ("header", [p.MAGIC + rng.bytes(40)]),  # random bytes after the magic (not 32 long)
        ("header", [p.MAGIC + rng.bytes(7), rng.bytes(13), rng.bytes(5)]),
        ("header", [patch(head, "<H", 6, 0x80), *payload]),  # unknown flag bit
        ("size", [head, *payload[:-1], payload[-1] * 2]),  # body larger than the header says
        ("size", [patch(head, "<I", 28, 1), *payload]),  # header says 1 byte
        ("frames", [head, *payload, b"extra", b"garbage"]),  # multi-frame garbage
        ("frames", [head]),  # payload frame missing
        ("oversized", [patch(head, "<I", 28, big), bytes(big)]),  # above MAX_PAYLOAD
    ]


def onset_payload_bad() -> Frames:
    head, body = p.encode(p.Message(p.Kind.ONSET, onset_rows(), seq=0))
    row = bytearray(body)
    row[8] = 200  # note 200
    return [head, bytes(row)]


def expected_counts(cases: list[tuple[str, Frames]]) -> Counter[str]:
    return Counter(kind for kind, _ in cases)


def check_table(cases: list[tuple[str, Frames]], pose_format: p.PoseFormat | None = None) -> None:
    """The table's kinds are what decode + kind_of say (so the service assertions mean it)."""
    for kind, frames in cases:
        if kind == "unexpected":
            continue
        with pytest.raises(p.ProtocolError) as info:
            p.decode(frames, pose_format)
        assert kind_of(info.value) == kind, f"{kind}: {info.value}"


def logged_once_per_kind(caplog: pytest.LogCaptureFixture, where: str, kinds: set[str]) -> None:
    lines = [r.getMessage() for r in caplog.records if r.getMessage().startswith(where + ":")]
    seen = Counter(
        kind for kind in kinds for line in lines if f"dropped a bad message ({kind})" in line
    )
    assert seen == Counter(dict.fromkeys(kinds, 1)), lines


def wait_for(cond: Callable[[], bool], timeout_s: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.005)
    return True


def xpub_peer(ctx: zmq.Context[zmq.Socket[bytes]]) -> tuple[zmq.Socket[bytes], str]:
    """The test's publisher; ``recv`` on it returns the subscriber's subscription."""
    sock = ctx.socket(zmq.XPUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.SNDHWM, 0)
    port = sock.bind_to_random_port("tcp://127.0.0.1")
    return sock, f"tcp://127.0.0.1:{port}"


def wait_subscribed(xpub: zmq.Socket[bytes]) -> bytes:
    assert xpub.poll(5000), "the service never subscribed"
    sub = xpub.recv()
    assert sub == b"\x01" + p.MAGIC, "services subscribe to every livedrummer message"
    return sub


def test_kind_of_maps_every_decode_error_to_a_short_kind() -> None:
    rng = np.random.default_rng(1)
    good = p.encode(p.Message(p.Kind.ONSET, onset_rows(), seq=0))
    cases = [*bad_messages(good, rng), ("payload", onset_payload_bad())]
    check_table(cases)
    bad = BadMessages("unit", logging.getLogger("test"))
    for _, frames in cases:
        with pytest.raises(p.ProtocolError) as info:
            p.decode(frames)
        bad.drop(info.value)
    bad.unexpected("HELLO")
    assert bad.summary() == {**expected_counts(cases), "unexpected": 1}
    assert bad.total == len(cases) + 1


# ---------------------------------------------------------------- the synth


def test_synth_drops_bad_input_and_control_messages_and_keeps_serving(
    ctx: zmq.Context[zmq.Socket[bytes]], caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    clock = MonotonicClock()
    rng = np.random.default_rng(7)
    pub, endpoint = xpub_peer(ctx)
    synth = LiveSynth(build_rig(load_kit("rock5")), SynthParams(0.01, 0.03))
    service = SynthService(synth, SynthConfig(sub=endpoint, pub=LOCAL, control=LOCAL), clock, ctx)
    eps = service.start()
    stop = threading.Event()
    thread = threading.Thread(target=service.run, args=(stop,), daemon=True)
    thread.start()
    poses = ctx.socket(zmq.SUB)
    poses.setsockopt(zmq.LINGER, 0)
    poses.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.POSE))
    poses.connect(eps["pub"])
    dealer = ctx.socket(zmq.DEALER)
    dealer.setsockopt(zmq.LINGER, 0)
    dealer.connect(eps["control"])
    try:
        wait_subscribed(pub)
        groove = read_midi_file(demo_groove(), load_note_map(DEMO_MAP)).onsets[:40].copy()
        groove["time_s"] += clock.now() - groove["time_s"][0] + 0.05
        template = p.encode(p.Message(p.Kind.ONSET, groove[:1], seq=0))
        cases = [
            *bad_messages(template, rng),
            ("payload", onset_payload_bad()),
            ("unexpected", p.encode(p.Message(p.Kind.HELLO, p.Hello("x", "y")))),
        ]
        check_table(cases)
        random.Random(7).shuffle(cases)
        filtered = [rng.bytes(64), b"garbage", b"LDR"]  # no magic: ZeroMQ drops them
        seq = 0
        for i in range(groove.size):  # good onsets interleaved with the bad messages
            pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, groove[i : i + 1], seq=seq)))
            seq += 1
            if i < len(cases):
                pub.send_multipart(cases[i][1])
            if i < len(filtered):
                pub.send_multipart([filtered[i]])
        assert len(cases) < len(groove)  # so the last message sent is a good one
        assert wait_for(lambda: service.stats.onsets == groove.size)
        # control socket: the same kinds of garbage around two HELLOs
        hello = p.encode(p.Message(p.Kind.HELLO, p.Hello("test", "probe"), stream=p.Stream.CONTROL))
        control_cases = [
            *bad_messages(hello, rng),
            ("header", [rng.bytes(50)]),  # random bytes: a ROUTER sees everything
            ("header", [b"junk", b"more", b"frames"]),
            ("frames", []),
            ("unexpected", p.encode(p.Message(p.Kind.HEARTBEAT))),
        ]
        check_table(control_cases[:-1])
        dealer.send_multipart([b"", *hello])
        for _, frames in control_cases:
            dealer.send_multipart([b"", *frames])
        dealer.send_multipart([b"", *hello])
        readies = []
        for _ in range(2):
            assert dealer.poll(5000), "the synth stopped answering HELLO"
            readies.append(p.decode(dealer.recv_multipart()[1:]))
        assert [m.kind for m in readies] == [p.Kind.READY, p.Kind.READY]
        assert not dealer.poll(200)  # nothing answered the garbage
        # poses still flow, and cover the good onsets' contacts
        got = 0
        deadline = time.monotonic() + 5
        while got < 5 and time.monotonic() < deadline:
            if poses.poll(100):
                msg = p.decode(poses.recv_multipart(), service.format)
                got += msg.kind is p.Kind.POSE
        assert got >= 5, "the synth stopped publishing poses"
        assert service.bad_events.summary() == expected_counts(cases)
        assert service.bad_control.summary() == expected_counts(control_cases)
        assert service.stats.missing == 0  # bad messages never look like lost ones
        assert service.stats.bad == len(cases)
        assert service.summary()["bad_messages"] == {
            "events": expected_counts(cases),
            "control": expected_counts(control_cases),
        }
        logged_once_per_kind(caplog, "synth input stream", set(expected_counts(cases)))
        logged_once_per_kind(caplog, "synth control socket", set(expected_counts(control_cases)))
    finally:
        stop.set()
        thread.join(5)
        for s in (pub, poses, dealer):
            s.close(0)
    assert not thread.is_alive()
    totals = [r.getMessage() for r in caplog.records if "dropped bad messages" in r.getMessage()]
    assert len(totals) == 2, "one on-exit total per socket"


# ---------------------------------------------------------------- the live display


def test_display_drops_bad_pose_messages_and_keeps_drawing_good_ones(
    ctx: zmq.Context[zmq.Socket[bytes]], caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    rng = np.random.default_rng(3)
    kit = load_kit("rock5")
    pub, endpoint = xpub_peer(ctx)
    config = LiveConfig(sub=endpoint, fps=100.0, render=False)
    display = LiveDisplay(kit, config, MonotonicFrameClock(), ctx)
    display.start()
    stop = threading.Event()
    thread = threading.Thread(target=display.run, args=(stop,), daemon=True)
    thread.start()
    try:
        wait_subscribed(pub)
        fmt = p.PoseFormat.from_dtype(pose_dtype(len(kit.pieces)))
        rows = np.zeros(4, fmt.dtype)
        rows["rotation"][..., 3] = 1.0
        rows["time_s"] = np.arange(4) * 0.0025
        now = time.monotonic()

        def pose(seq: int) -> Frames:
            return p.encode(
                p.Message(
                    p.Kind.POSE, p.Pose(now + seq * 0.01, rows), seq=seq, stream=p.Stream.POSES
                ),
                fmt,
            )

        other = p.PoseFormat.from_dtype(pose_dtype(len(kit.pieces) + 1))
        wrong_rows = np.zeros(4, other.dtype)
        cases = [
            *bad_messages(pose(0), rng),
            ("payload", p.encode(p.Message(p.Kind.POSE, p.Pose(now, wrong_rows)), other)),
            ("unexpected", p.encode(p.Message(p.Kind.ONSET, onset_rows()))),
        ]
        check_table(cases, fmt)
        good = 30
        for seq in range(good):
            pub.send_multipart(pose(seq))
            if seq < len(cases):
                pub.send_multipart(cases[seq][1])
            if seq < 3:
                pub.send_multipart([rng.bytes(40)])  # no magic: filtered by ZeroMQ
        assert wait_for(lambda: display.stats.pose_messages == good)
        assert wait_for(lambda: display.stats.frames > 5)  # still drawing
        assert display.bad.summary() == expected_counts(cases)
        assert display.stats.bad == len(cases)
        assert display.stats.missing == 0
        assert display.summary()["bad_messages"] == expected_counts(cases)
        logged_once_per_kind(caplog, "display pose stream", set(expected_counts(cases)))
    finally:
        stop.set()
        thread.join(5)
        pub.close(0)
    assert not thread.is_alive()


# ---------------------------------------------------------------- the input daemon


def test_input_daemon_control_socket_counts_each_kind_and_keeps_answering_hello(
    ctx: zmq.Context[zmq.Socket[bytes]], caplog: pytest.LogCaptureFixture, tmp_path: Path
) -> None:
    caplog.set_level(logging.WARNING)
    rng = np.random.default_rng(11)
    clock = MonotonicClock()
    src = FileSource(demo_groove(), clock, load_note_map(DEMO_MAP))
    src.load()
    config = DaemonConfig(
        pub=LOCAL, control=LOCAL, wait_subscribers=99, sessions_dir=tmp_path / "sessions"
    )
    daemon = InputDaemon(src, config, clock, ctx)
    eps = daemon.start()
    stop = threading.Event()
    thread = threading.Thread(target=daemon.run, args=(stop,), daemon=True)
    thread.start()
    dealer = ctx.socket(zmq.DEALER)
    dealer.setsockopt(zmq.LINGER, 0)
    dealer.connect(eps["control"])
    try:
        hello = p.encode(p.Message(p.Kind.HELLO, p.Hello("test", "probe"), stream=p.Stream.CONTROL))
        bad_hello = bytearray(hello[1])
        bad_hello[0:1] = b"["
        cases = [
            *bad_messages(hello, rng),
            ("payload", [hello[0], bytes(bad_hello)]),  # HELLO body not a JSON object
            ("header", [rng.bytes(31)]),
            ("header", [rng.bytes(33), rng.bytes(2)]),
            ("frames", []),
            ("unexpected", p.encode(p.Message(p.Kind.ONSET, onset_rows()))),
            ("unexpected", p.encode(p.Message(p.Kind.READY, p.Hello("x", "y")))),
        ]
        check_table(cases)
        answered = 0
        for _, frames in cases:
            dealer.send_multipart([b"", *hello])
            dealer.send_multipart([b"", *frames])
            assert dealer.poll(5000), "the daemon stopped answering HELLO"
            reply = p.decode(dealer.recv_multipart()[1:])
            answered += reply.kind is p.Kind.READY and isinstance(reply.body, p.Hello)
        dealer.send_multipart([b"", *hello])
        assert dealer.poll(5000)
        dealer.recv_multipart()
        assert answered == len(cases)
        assert not dealer.poll(200)  # nothing answered the garbage
        expected = expected_counts(cases)
        assert daemon.bad_control.summary() == expected
        assert daemon.summary()["bad_messages"] == {"control": expected}
        assert daemon.problems.counts["bad control message"] == len(cases) - 2
        assert daemon.problems.counts["unexpected control message"] == 2
        logged_once_per_kind(caplog, "input control socket", set(expected))
    finally:
        stop.set()
        thread.join(5)
        dealer.close(0)
    assert not thread.is_alive()


# ---------------------------------------------------------------- the remote source


def test_remote_source_counts_each_kind_and_relays_every_good_onset(
    ctx: zmq.Context[zmq.Socket[bytes]], caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.WARNING)
    rng = np.random.default_rng(5)
    pub, endpoint = xpub_peer(ctx)
    clock = MonotonicClock()
    src = RemoteSource(endpoint, clock, ctx)
    src.open()
    try:
        wait_subscribed(pub)
        template = p.encode(p.Message(p.Kind.ONSET, onset_rows(), seq=0))
        cases: list[tuple[str, Frames]] = [
            *bad_messages(template, rng),
            ("payload", onset_payload_bad()),
            ("unexpected", p.encode(p.Message(p.Kind.HELLO, p.Hello("x", "y")))),
        ]
        check_table(cases)
        good = 20
        for seq in range(good):
            pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, onset_rows(2, 36 + seq), seq=seq)))
            if seq < len(cases):
                pub.send_multipart(cases[seq][1])
            pub.send_multipart([rng.bytes(32)])  # no magic: filtered by ZeroMQ
        events: list[Any] = []
        deadline = time.monotonic() + 5
        while len(events) < 2 * good and time.monotonic() < deadline:
            events.extend(src.read(0.05))
        assert [e.note for e in events] == [36 + i // 2 for i in range(2 * good)]
        assert src.bad.summary() == expected_counts(cases)
        assert src.problems.counts["bad remote message"] == len(cases)
        assert src.tracker.stats[(0, 0)].missing == 0
        logged_once_per_kind(caplog, f"remote {endpoint}", set(expected_counts(cases)))
    finally:
        src.close()
        pub.close(0)
