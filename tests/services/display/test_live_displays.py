"""Several displays on one synth (a projector and a monitor): each gets every pose.

Real sockets on loopback: the test publishes onsets as an input daemon would, one synth
service turns them into poses, two live displays subscribe to the synth (render off, frames
logged) and must both hold the contact sample of every hand note at onset + D.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import zmq

from livedrummer import protocol as p
from livedrummer.body.rig import build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.live.track import PoseTrack
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.sticking.online import stick_online
from livedrummer.timeline.clock import MonotonicClock
from services.cli.files import DEMO_MAP, demo_groove
from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock
from services.synth.service import SynthConfig, SynthService

LOCAL = "tcp://127.0.0.1:*"


def wait_for(cond: Callable[[], bool], timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_two_displays_on_one_synth_both_get_every_contact(tmp_path: Path) -> None:
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    clock = MonotonicClock()
    kit = load_kit("rock5")
    params = SynthParams()
    pub = ctx.socket(zmq.XPUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    synth = SynthService(
        LiveSynth(build_rig(kit), params),
        SynthConfig(sub=f"tcp://127.0.0.1:{port}", pub=LOCAL, control=LOCAL),
        clock,
        ctx,
    )
    eps = synth.start()
    stop = threading.Event()
    threads = [threading.Thread(target=synth.run, args=(stop,), daemon=True)]
    displays = []
    for k in range(2):
        cfg = LiveConfig(sub=eps["pub"], fps=30.0, render=False, out=tmp_path / f"d{k}")
        d = LiveDisplay(kit, cfg, MonotonicFrameClock(), ctx)
        d.track = PoseTrack(keep_s=30.0)  # keep the whole test, not the show's last 3 s
        d.start()
        displays.append(d)
        threads.append(threading.Thread(target=d.run, args=(stop,), daemon=True))
    for t in threads:
        t.start()
    try:
        assert pub.poll(5000), "the synth never subscribed"
        pub.recv()
        # both displays' subscriptions reach the synth's PUB before the first pose matters
        time.sleep(0.3)
        onsets = read_midi_file(demo_groove(), load_note_map(DEMO_MAP)).onsets
        onsets = onsets[onsets["time_s"] < 5.0].copy()
        onsets["time_s"] += clock.now() + 0.2 - float(onsets["time_s"][0])
        for seq, row in enumerate(onsets):
            while clock.now() < float(row["time_s"]):
                time.sleep(0.001)
            pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, onsets[seq : seq + 1], seq=seq)))
        last = float(onsets["time_s"][-1]) + params.delay_s
        assert wait_for(lambda: all((d.track.newest_s or 0.0) > last + 0.1 for d in displays))
    finally:
        stop.set()
        for t in threads:
            t.join(5.0)
        pub.close(0)
        ctx.destroy(0)
    sticking = stick_online(onsets, kit, params.lookahead_s)
    hands = (sticking.limb >= 0) & (sticking.limb <= 1) & (sticking.piece >= 0)
    contacts = sticking.onsets["time_s"][hands].astype(np.float64) + params.delay_s
    assert contacts.size >= 10
    for d in displays:
        assert d.stats.pose_messages > 10 and d.stats.missing == 0
        kept = d.track.show_s
        for t in contacts:
            assert np.min(np.abs(kept - t)) < 1e-6, f"a display lacks the contact at {t}"
