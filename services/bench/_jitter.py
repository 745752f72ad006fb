"""A jittery network on loopback, for the remote-timing test and benchmark.

:func:`jitter_relay` forwards a PUB stream with every message delayed by a random 20-60 ms
(``low_s..high_s``), in order, as TCP delivers a path whose queueing varies: a message never
overtakes the one before it. :func:`control_proxy` carries DEALER/ROUTER exchanges (a clock
exchange) with each direction delayed by a random ``0..max_s``, so round trips are uneven as
on a real network. Both run until ``stop`` and append their bound endpoint to ``bound``.
:class:`AheadClock` is the remote site's clock: ours plus a known offset.
:func:`remote_session` puts them together: a remote site, the network, and the real
``livedrummer input --remote`` process, recording both sides' onsets.
"""

from __future__ import annotations

import collections
import json
import os
import random
import signal
import subprocess
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import zmq

from livedrummer.timeline.clock import MonotonicClock

from ._paths import WORKDIR


class AheadClock(MonotonicClock):
    """A clock ``offset_s`` ahead of this machine's shared clock (a remote site's)."""

    def __init__(self, offset_s: float) -> None:
        self.offset_s = offset_s

    def now(self) -> float:
        return super().now() + self.offset_s


def jitter_relay(
    ctx: zmq.Context[zmq.Socket[bytes]],
    upstream: str,
    stop: threading.Event,
    bound: list[str],
    low_s: float = 0.020,
    high_s: float = 0.060,
    seed: int = 11,
) -> None:
    """SUB from ``upstream``, PUB on, each message ``low_s..high_s`` later, in order."""
    rng = random.Random(seed)
    sub, pub = ctx.socket(zmq.SUB), ctx.socket(zmq.PUB)
    for s in (sub, pub):
        s.setsockopt(zmq.LINGER, 0)
    sub.setsockopt(zmq.SUBSCRIBE, b"")
    sub.connect(upstream)
    bound.append(f"tcp://127.0.0.1:{pub.bind_to_random_port('tcp://127.0.0.1')}")
    queue: collections.deque[tuple[float, list[bytes]]] = collections.deque()
    last = 0.0
    while not stop.is_set():
        wait = 10 if not queue else max(0, int((queue[0][0] - time.monotonic()) * 1000))
        if sub.poll(wait):
            frames = sub.recv_multipart()
            last = max(time.monotonic() + rng.uniform(low_s, high_s), last)
            queue.append((last, frames))
        while queue and queue[0][0] <= time.monotonic():
            pub.send_multipart(queue.popleft()[1])
    sub.close(0)
    pub.close(0)


def control_proxy(
    ctx: zmq.Context[zmq.Socket[bytes]],
    upstream: str,
    stop: threading.Event,
    bound: list[str],
    max_s: float = 0.010,
    seed: int = 5,
) -> None:
    """ROUTER for one client's exchanges, DEALER on to ``upstream``; each way ``0..max_s``."""
    rng = random.Random(seed)
    front, back = ctx.socket(zmq.ROUTER), ctx.socket(zmq.DEALER)
    for s in (front, back):
        s.setsockopt(zmq.LINGER, 0)
    bound.append(f"tcp://127.0.0.1:{front.bind_to_random_port('tcp://127.0.0.1')}")
    back.connect(upstream)
    ups: collections.deque[tuple[float, list[bytes]]] = collections.deque()
    downs: collections.deque[tuple[float, list[bytes]]] = collections.deque()
    client = b""
    poller = zmq.Poller()
    poller.register(front, zmq.POLLIN)
    poller.register(back, zmq.POLLIN)
    while not stop.is_set():
        due = min([q[0][0] for q in (ups, downs) if q], default=time.monotonic() + 0.05)
        events = dict(poller.poll(max(0, int((due - time.monotonic()) * 1000))))
        now = time.monotonic()
        if front in events:
            client, *rest = front.recv_multipart()
            ups.append((now + rng.uniform(0, max_s), rest))
        if back in events:
            downs.append((now + rng.uniform(0, max_s), back.recv_multipart()))
        while ups and ups[0][0] <= now:
            back.send_multipart(ups.popleft()[1])
        while downs and downs[0][0] <= now:
            front.send_multipart([client, *downs.popleft()[1]])
    front.close(0)
    back.close(0)


@dataclass
class RemoteSession:
    """What one run of :func:`remote_session` saw."""

    sent: list[float]  # onset stamps as the remote site played them (its clock)
    got: list[float]  # the same onsets as the local input daemon published them (our clock)
    summary: str  # the local daemon's stderr (its exit line has the clock figures)


def remote_session(
    seconds: float, *, control: bool, offset_s: float, home: str, err_path: Path
) -> RemoteSession:
    """A remote site (an input daemon playing the demo groove on a clock ``offset_s`` ahead)
    reached through :func:`jitter_relay` (and, with ``control``, its control socket through
    :func:`control_proxy`) by a local ``livedrummer input --remote`` process; ``seconds`` of
    both sides' onsets."""
    from livedrummer import protocol as p
    from livedrummer.midi.notemap import load_note_map

    from ..cli.files import DEMO_MAP, demo_groove
    from ..input.daemon import DaemonConfig, InputDaemon
    from ..input.fileplayer import FileSource
    from ..process.program import program_argv

    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    remote_clock = AheadClock(offset_s)
    source = FileSource(demo_groove(), remote_clock, load_note_map(DEMO_MAP))
    source.load()
    local = "tcp://127.0.0.1:*"
    daemon = InputDaemon(
        source,
        DaemonConfig(pub=local, control=local, journal=False, wait_subscribers=2),
        remote_clock,
        ctx,
    )
    eps = daemon.start()
    stop = threading.Event()
    relay_at: list[str] = []
    proxy_at: list[str] = []
    threads = [
        threading.Thread(target=daemon.run, args=(stop,), daemon=True),
        threading.Thread(target=jitter_relay, args=(ctx, eps["pub"], stop, relay_at)),
        threading.Thread(target=control_proxy, args=(ctx, eps["control"], stop, proxy_at)),
    ]
    for t in threads[1:]:
        t.start()
    while not relay_at or not proxy_at:
        time.sleep(0.01)
    played, heard = ctx.socket(zmq.SUB), ctx.socket(zmq.SUB)
    for s in (played, heard):
        s.setsockopt(zmq.SUBSCRIBE, b"")
        s.setsockopt(zmq.LINGER, 0)
    played.connect(eps["pub"])
    extra = ["--remote-control", proxy_at[0]] if control else []
    with err_path.open("w") as err:
        proc = subprocess.Popen(
            [
                *program_argv(
                    "input",
                    "--remote",
                    relay_at[0],
                    *extra,
                    "--pub",
                    local,
                    "--control",
                    local,
                    "--no-journal",
                )
            ],
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
            cwd=WORKDIR,
            env={**os.environ, "LIVEDRUMMER_HOME": home},
        )
    sent: list[float] = []
    got: list[float] = []
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"input --remote did not start: {err_path.read_text()[-800:]}")
        heard.connect(json.loads(line)["pub"])
        time.sleep(0.5)  # the local daemon's and the relay's subscriptions are in
        threads[0].start()  # the remote site starts playing
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for sock, into in ((played, sent), (heard, got)):
                while sock.poll(0):
                    msg = p.decode(sock.recv_multipart())
                    if msg.kind is p.Kind.ONSET:
                        into.extend(msg.rows["time_s"].astype(float).tolist())
            time.sleep(0.002)
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        stop.set()
        for t in threads:
            if t.is_alive():
                t.join(5)
        played.close(0)
        heard.close(0)
        daemon.shutdown()
        ctx.term()
    return RemoteSession(sent, got, err_path.read_text())
