"""The synth's answer path: a hit is answered while the window is being re-animated, and the
two-threaded service's poses at contacts equal its offline twin's.

The first test holds a re-animation in the middle (the animation thread inside
``CurveSet.rebuild``) and answers a hit from another thread meanwhile: the hit's contact
comes out without waiting for the re-animation to end. The second plays the demo groove
through a real synth service on loopback sockets and compares every hand note's contact, as
published, with the offline animation of the same sticking (stick tip within
:data:`TIP_TOLERANCE_M`), and every quick answer with the struck target.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.body.animation import animate, hihat_openness
from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import Rig
from livedrummer.body.skeleton import J
from livedrummer.live.synth import LiveSynth, PoseBatch, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.sticking.online import stick_online
from livedrummer.timeline.clock import MonotonicClock
from livedrummer.timeline.events import CONTROL_DTYPE
from livedrummer.timeline.performance import Performance
from services.synth.service import SynthConfig, SynthService

START = 5000.0
TIPS = {0: J["r_tip"], 1: J["l_tip"]}
#: a published contact's stick tip against the offline animation's at the same onset
TIP_TOLERANCE_M = 0.003
LOCAL = "tcp://127.0.0.1:*"


def test_a_hit_is_answered_while_the_window_is_re_animated(
    rig: Rig, groove: Performance, monkeypatch: pytest.MonkeyPatch
) -> None:
    synth = LiveSynth(rig, SynthParams())
    onsets = groove.onsets[groove.onsets["time_s"] < 3.0].copy()
    onsets["time_s"] += START
    k = onsets.size // 2
    while onsets["time_s"][k + 1] - onsets["time_s"][k] < 0.02:
        k += 1
    now = float(onsets["time_s"][0]) - 0.2
    for row in onsets[: k + 1]:
        while now + 1 / 120 < float(row["time_s"]):
            now += 1 / 120
            synth.poses_until(now)
        synth.process(row)
        synth.take_quick()
    lock = threading.Lock()
    inside, go = threading.Event(), threading.Event()
    rebuild = synth.curves.rebuild

    def held(*args, **kwargs):  # type: ignore[no-untyped-def]
        inside.set()
        assert go.wait(10.0)
        return rebuild(*args, **kwargs)

    monkeypatch.setattr(synth.curves, "rebuild", held)
    out: list[PoseBatch] = []

    def animate_window() -> None:
        with lock:
            out.append(synth.poses_until(now + 1 / 120, lock=lock))

    worker = threading.Thread(target=animate_window, daemon=True)
    worker.start()
    try:
        assert inside.wait(10.0), "the window was not re-animated"
        hit = onsets[k + 1].copy()
        hit["time_s"] = now + 1 / 120 + 0.001
        assert lock.acquire(timeout=5.0), "the re-animation holds the lock"
        try:  # the re-animation is still under way
            assert not go.is_set() and worker.is_alive()
            synth.process(hit)
            quick = synth.take_quick()
        finally:
            lock.release()
    finally:
        go.set()
        worker.join(10.0)
    show = float(hit["time_s"]) + synth.params.delay_s
    assert quick.show_s.size and quick.show_s[-1] == pytest.approx(show, abs=1e-9)
    assert out, "the re-animation finished after the answer"
    later = synth.poses_until(float(hit["time_s"]) + 0.002)
    assert np.any(np.abs(later.show_s - show) < 1e-9), "the hit's contact stays on the track"


def test_the_service_s_contacts_equal_the_offline_twin_s(rig: Rig, groove: Performance) -> None:
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    clock = MonotonicClock()
    params = SynthParams()
    pub = ctx.socket(zmq.XPUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    service = SynthService(
        LiveSynth(rig, params),
        SynthConfig(sub=f"tcp://127.0.0.1:{port}", pub=LOCAL, control=LOCAL),
        clock,
        ctx,
    )
    eps = service.start()
    stop = threading.Event()
    thread = threading.Thread(target=service.run, args=(stop,), daemon=True)
    poses = ctx.socket(zmq.SUB)
    poses.setsockopt(zmq.LINGER, 0)
    poses.setsockopt(zmq.RCVHWM, 0)
    poses.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.POSE))
    poses.connect(eps["pub"])
    fmt = p.PoseFormat.from_dtype(pose_dtype(len(rig.kit.pieces)))
    track = PoseTrack(keep_s=30.0)
    first: dict[float, np.ndarray] = {}  # show time -> the first record published for it
    thread.start()
    try:
        assert pub.poll(5000), "the synth never subscribed"
        pub.recv()
        time.sleep(0.2)
        onsets = groove.onsets[groove.onsets["time_s"] < 4.0].copy()
        onsets["time_s"] += clock.now() + 0.2 - float(onsets["time_s"][0])
        shows = np.sort(onsets["time_s"].astype(np.float64) + params.delay_s)
        end = float(onsets["time_s"][-1]) + 0.3
        seq = 0

        def take(until: float) -> None:
            while (left := until - clock.now()) > 0:
                if not poses.poll(max(1, int(left * 1000))):
                    continue
                msg = p.decode(poses.recv_multipart(), fmt)
                assert isinstance(msg.body, p.Pose)
                show = msg.body.time_s + msg.body.rows["time_s"].astype(np.float64)
                track.add(show, msg.body.rows)
                i = np.clip(np.searchsorted(shows, show), 1, shows.size - 1)
                i = np.where(shows[i] - show < show - shows[i - 1], i, i - 1)
                for j in np.flatnonzero(np.abs(shows[i] - show) < 1e-6):
                    first.setdefault(float(shows[i[j]]), msg.body.rows[j].copy())

        while seq < onsets.size:
            take(float(onsets["time_s"][seq]))
            pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, onsets[seq : seq + 1], seq=seq)))
            seq += 1
        take(end)
    finally:
        stop.set()
        thread.join(5.0)
        poses.close(0)
        pub.close(0)
        ctx.destroy(0)
    assert not thread.is_alive()
    sticking = stick_online(onsets, rig.kit, params.lookahead_s)
    hands = np.flatnonzero((sticking.limb >= 0) & (sticking.limb <= 1) & (sticking.piece >= 0))
    assert hands.size > 10
    anim = animate(rig, sticking, np.zeros(0), hihat_openness(onsets, np.zeros(0, CONTROL_DTYPE)))
    _, world = anim.world(sticking.onsets["time_s"][hands].astype(np.float64))
    answered_on_target = 0
    for k, i in enumerate(hands):
        row, limb = sticking.onsets[i], int(sticking.limb[i])
        show = float(row["time_s"]) + params.delay_s
        j = int(np.argmin(np.abs(track.show_s - show)))
        assert abs(track.show_s[j] - show) < 1e-6, f"no sample at onset {i} + D"
        tip = TIPS[limb]
        miss = float(np.linalg.norm(track.rows["position"][j, tip] - world[k, tip]))
        assert miss < TIP_TOLERANCE_M, f"onset {i}: tip {miss * 1000:.1f} mm off the offline one"
        # the answer (the first record sent for it): the same tip, unless its provisional hand
        # was the other one
        quick = first[show]["position"][tip].astype(np.float64)
        answered_on_target += bool(np.linalg.norm(quick - world[k, tip]) < TIP_TOLERANCE_M)
    assert answered_on_target >= 0.95 * hands.size, f"{answered_on_target} of {hands.size}"
    assert service.stats.onsets == onsets.size and service.synth.quick_contacts == onsets.size
