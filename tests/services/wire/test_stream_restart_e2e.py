"""End to end on loopback: a synth-like publisher that skips, sends junk and restarts.

A live display and a stage display run their own loops (rendering off) on one pose stream.
The publisher sends poses with three numbers skipped and two bad messages, then goes away
and a new one binds the same port and numbers from 2 (its 0 and 1 sent before the displays
reconnected: the restart is seen by its fresh send time). Both displays keep drawing, and
both report the same: 3 missing, 1 restart, 2 bad, every pose that reached them taken.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.pose import pose_dtype
from livedrummer.kit.loader import load_kit
from livedrummer.stage.formation import Placement
from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock
from services.display.stage_live import StageConfig, StageDisplay, StagePerformer
from services.wire.stream_rx import Counts

PERFORMER = 1


def wait_for(cond: Callable[[], bool], timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def publisher(
    ctx: zmq.Context[zmq.Socket[bytes]], port: int, subscribers: int
) -> zmq.Socket[bytes]:
    """An XPUB on ``port`` (retried while the old one's port is let go), returned once
    ``subscribers`` have subscribed (verbose: each subscription is seen)."""
    sock = ctx.socket(zmq.XPUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.XPUB_VERBOSE, 1)
    deadline = time.monotonic() + 5
    while True:
        try:
            sock.bind(f"tcp://127.0.0.1:{port}")
            break
        except zmq.ZMQError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.05)
    for _ in range(subscribers):
        assert sock.poll(10_000), "a display never (re)subscribed"
        sock.recv()
    return sock


def test_both_displays_ride_out_a_skipping_junk_sending_restarting_synth() -> None:
    kit = load_kit("rock5")
    fmt = p.PoseFormat.from_dtype(pose_dtype(len(kit.pieces)))
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    probe = ctx.socket(zmq.PUB)
    port = probe.bind_to_random_port("tcp://127.0.0.1")
    probe.close(0)
    endpoint = f"tcp://127.0.0.1:{port}"
    clock = MonotonicFrameClock()
    live = LiveDisplay(kit, LiveConfig(sub=endpoint, fps=50.0, render=False), clock, ctx)
    who = [StagePerformer("a", PERFORMER, endpoint, kit, Placement(0.0, 0.0, 0.0))]
    stage = StageDisplay(who, StageConfig(fps=50.0, render=False), clock, ctx)
    stop = threading.Event()
    threads = []
    for d in (live, stage):
        d.start()
        threads.append(threading.Thread(target=d.run, args=(stop,), daemon=True))
        threads[-1].start()

    def pose(seq: int) -> list[bytes]:
        now = clock.now()
        rows = np.zeros(3, fmt.dtype)
        rows["rotation"][..., 3] = 1.0
        rows["time_s"] = np.arange(3) / 240
        msg = p.Message(p.Kind.POSE, p.Pose(now, rows), PERFORMER, seq, now, p.Stream.POSES)
        return p.encode(msg, fmt)

    rxs = [live.stream.rx, stage.streams[0].rx]
    try:
        first = publisher(ctx, port, 2)
        for seq in [*range(10), *range(13, 16)]:  # 10, 11, 12 lost
            first.send_multipart(pose(seq))
            if seq == 4:
                first.send_multipart([p.MAGIC + b"\x01" * 11])  # junk
                hello = p.Message(p.Kind.HELLO, p.Hello("x", "y"), PERFORMER, 5)
                first.send_multipart(p.encode(hello))  # a kind a pose stream does not serve
        assert wait_for(lambda: all(rx.counts.received == 13 for rx in rxs))
        first.close(0)  # the synth goes away ...
        again = publisher(ctx, port, 2)  # ... and a new one comes up on its port
        for seq in range(2, 10):
            again.send_multipart(pose(seq))
        assert wait_for(lambda: all(rx.counts.received == 21 for rx in rxs))
        frames = (live.stats.frames, stage.frames)
        assert wait_for(lambda: live.stats.frames > frames[0] and stage.frames > frames[1])
        assert all(t.is_alive() for t in threads)
        again.close(0)
    finally:
        stop.set()
        for t in threads:
            t.join(5)
        ctx.destroy(0)
    want = Counts(received=21, missing=3, duplicates=0, restarts=1, bad=2)
    assert [rx.counts for rx in rxs] == [want, want]
    a = stage.summary()["performers"]["a"]
    assert (a["pose_messages"], a["missing"], a["bad"], a["restarts"]) == (21, 3, 2, 1), a
    s = live.summary()
    assert (s["pose_messages"], s["missing"], s["bad"]) == (21, 3, 2), s
    assert live.stream.stats.restarts == 1
