"""A remote drummer's timing kept across a jittery network: clock offset and jitter buffer.

The estimators are pure (:mod:`livedrummer.live.clocksync`) and are tested on exchanges with a
known offset, drift and random queueing. End to end, with real sockets on loopback: a remote
site (an input daemon playing the demo groove on a clock 753.1 ms ahead of ours) is reached
through a relay the test runs, which delays every event message by 20-60 ms of random jitter
(in order, as TCP delivers), and through a proxy that delays each clock exchange by 0-10 ms
each way; the local ``livedrummer input --remote --remote-control`` runs as its own process.
The intervals between the hits it publishes must match the intervals played within 2 ms at
p99, and its offset estimate must be within 1 ms.
"""

from __future__ import annotations

import random
import re
from pathlib import Path

import numpy as np
import pytest

from livedrummer.live.clocksync import ClockSync, JitterBuffer, SyncSample
from services.bench._jitter import remote_session
from services.bench.remote_timing import OFFSET_S, intervals


def test_offset_and_drift_come_out_of_queueing_noise() -> None:
    rng = random.Random(7)
    drift = 50e-6
    remote = lambda t: t + OFFSET_S + drift * (t - 100.0)  # noqa: E731
    sync = ClockSync()
    t = 100.0
    for _ in range(300):  # one exchange every 0.2 s for 60 s
        up = 0.002 + rng.expovariate(1 / 0.010)  # 2 ms of wire plus queueing, each way
        down = 0.002 + rng.expovariate(1 / 0.010)
        work = rng.uniform(0, 0.0005)
        sync.add(SyncSample(t, remote(t + up + work), t + up + work + down))
        t += 0.2
    truth = OFFSET_S + drift * (t - 100.0)
    assert abs(sync.offset_at(t) - truth) < 0.0005
    assert abs(sync.drift - drift) < 20e-6
    assert abs(sync.to_local(remote(t)) - t) < 0.0005
    assert sync.uncertainty_s < 0.003


def test_a_stepped_clock_sample_is_ignored_and_no_sample_is_no_estimate() -> None:
    sync = ClockSync()
    assert not sync.ready
    with pytest.raises(ValueError):
        sync.offset_at(0.0)
    sync.add(SyncSample(2.0, 5.0, 1.0))  # received before sent: our clock stepped
    assert not sync.ready


def test_the_buffer_rises_at_once_and_falls_slowly() -> None:
    rng = random.Random(3)
    buf = JitterBuffer(fall_rate=0.002)
    now = 0.0
    for _ in range(500):  # 20-60 ms of jitter
        buf.observe(rng.uniform(0.020, 0.060), now)
        now += 0.05
    assert buf.delay_s is not None and 0.058 < buf.delay_s < 0.063
    assert buf.observe(0.090, now) < 0.065  # one straggler is not a worse network ...
    for _ in range(4):  # ... a worse path is: the delay follows within a fifth of a second
        now += 0.05
        worse = buf.observe(rng.uniform(0.080, 0.100), now)
    assert worse >= 0.080
    start, start_delay = now, worse
    for _ in range(200):  # 10 s of a better path, 5-10 ms
        now += 0.05
        buf.observe(rng.uniform(0.005, 0.010), now)
    assert buf.delay_s is not None
    assert start_delay - buf.delay_s <= 0.002 * (now - start) + 1e-9  # never faster than the rate
    for _ in range(1200):  # a minute later it has come down to the new jitter
        now += 0.05
        buf.observe(rng.uniform(0.005, 0.010), now)
    assert buf.delay_s < 0.013
    assert buf.playout(now - 0.1, now) == now and buf.late == 1  # already due: played now


def test_a_remote_drummers_intervals_survive_network_jitter(tmp_path: Path) -> None:
    run = remote_session(
        16.0,
        control=True,
        offset_s=OFFSET_S,
        home=str(tmp_path / "home"),
        err_path=tmp_path / "input.err",
    )
    summary = run.summary
    m = re.search(
        r"remote clock ([+-][\d.]+) ms \(\+/- ([\d.]+)\).*played ([\d.]+) ms behind", summary
    )
    assert m, summary
    offset_ms, delay_ms = float(m.group(1)), float(m.group(3))
    assert abs(offset_ms - 1000 * OFFSET_S) < 1.0, summary
    assert 40.0 < delay_ms < 200.0, summary  # the relay's 20-60 ms at least, and the margin
    n = min(len(run.sent), len(run.got))
    assert n > 80 and abs(len(run.sent) - len(run.got)) <= 2, (len(run.sent), len(run.got))
    # Hits from 3 s on: the first exchanges and the buffer's first second of transits set up
    # the mapping; from then the delay only moves by the last fraction of the jitter's range.
    err_ms, lag = intervals(run.sent, run.got, 3.0)
    assert np.percentile(err_ms, 99) <= 2.0, (np.sort(err_ms)[-5:], summary)
    # and the delay each hit was played with is the network's plus the buffer, not more
    assert 0.040 < float(np.median(lag)) < 0.200
