"""``livedrummer relay``: a synth's poses through a tree of relays, byte for byte.

Real parts on loopback: a synth service turns the demo groove's onsets (published by the test
as an input daemon would) into poses; two relays run as their own processes, the second
chained under the first; subscribers on the synth, on the first relay and on the second must
all hold the same POSE messages, the synth's own bytes with its sequence numbers, and each
relay answers HELLO with the synth's pose format and avatar.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.body.rig import build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.live.synth import LiveSynth, SynthParams
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import MonotonicClock
from livedrummer.timeline.events import CONTROL_DTYPE
from services.cli.files import DEMO_MAP, demo_groove
from services.synth.service import SynthConfig, SynthService
from services.wire.net import request_ready

REPO = Path(__file__).resolve().parents[3]
LOCAL = "tcp://127.0.0.1:*"


def relay(tmp: Path, name: str, *args: str) -> tuple[subprocess.Popen[str], dict[str, Any]]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "services", "relay", "--pub", LOCAL, "--control", LOCAL, *args],
        stdout=subprocess.PIPE,
        stderr=(tmp / f"{name}.err").open("w"),
        text=True,
        cwd=REPO,
        env={**os.environ, "LIVEDRUMMER_HOME": str(tmp / "home")},
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line, (tmp / f"{name}.err").read_text()
    return proc, json.loads(line)


def stop(proc: subprocess.Popen[str]) -> int:
    proc.send_signal(signal.SIGTERM)
    try:
        return proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait()


def test_poses_reach_every_display_through_a_tree_of_relays(tmp_path: Path) -> None:
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    clock = MonotonicClock()
    kit = load_kit("rock5")
    params = SynthParams()
    pub = ctx.socket(zmq.XPUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    synth = SynthService(
        LiveSynth(build_rig(kit), params),
        SynthConfig(
            sub=f"tcp://127.0.0.1:{port}",
            pub=LOCAL,
            control=LOCAL,
            performer=7,
            avatar="0123456789abcdef",
        ),
        clock,
        ctx,
    )
    eps = synth.start()
    stop_synth = threading.Event()
    thread = threading.Thread(target=synth.run, args=(stop_synth,), daemon=True)
    thread.start()
    procs: list[subprocess.Popen[str]] = []
    subs: list[zmq.Socket[bytes]] = []
    try:
        first, first_eps = relay(
            tmp_path, "relay1", "--upstream", eps["pub"], "--upstream-control", eps["control"]
        )
        procs.append(first)
        second, second_eps = relay(
            tmp_path,
            "relay2",
            "--upstream",
            first_eps["pub"],
            "--upstream-control",
            first_eps["control"],
        )
        procs.append(second)
        for hello_from in (first_eps, second_eps):
            ready = request_ready(ctx, hello_from["control"], p.Hello("test", "frames"), 5.0)
            assert (ready.service, ready.performer, ready.avatar) == (
                "relay",
                7,
                "0123456789abcdef",
            )
            assert ready.pose is not None and ready.pose.hash == synth.format.hash
        where = [eps["pub"]] + [first_eps["pub"]] * 3 + [second_eps["pub"]] * 2
        for endpoint in where:
            s = ctx.socket(zmq.SUB)
            s.setsockopt(zmq.LINGER, 0)
            s.setsockopt(zmq.SUBSCRIBE, p.MAGIC)
            s.connect(endpoint)
            subs.append(s)
        assert pub.poll(5000), "the synth never subscribed"
        pub.recv()
        time.sleep(0.5)  # subscriptions climb the tree (each relay passes its own up at once)
        onsets = read_midi_file(demo_groove(), load_note_map(DEMO_MAP)).onsets
        onsets = onsets[onsets["time_s"] < 3.0].copy()
        onsets["time_s"] += clock.now() + 0.2 - float(onsets["time_s"][0])
        for seq, row in enumerate(onsets):
            while clock.now() < float(row["time_s"]):
                time.sleep(0.001)
            pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, onsets[seq : seq + 1], seq=seq)))
        grab = np.zeros(1, CONTROL_DTYPE)  # a cymbal grab: forwarded as SHOWN_CONTROL
        grab["time_s"], grab["kind"], grab["number"], grab["value"] = clock.now(), 1, 49, 127
        pub.send_multipart(p.encode(p.Message(p.Kind.CONTROL, grab, seq=len(onsets))))
        time.sleep(0.5)
        stop_synth.set()  # the synth publishes poses as long as it runs: stop, then compare
        thread.join(5)
        time.sleep(0.3)
        got: list[list[tuple[int, bytes]]] = []
        for s in subs:
            msgs = []
            while s.poll(300):
                frames = s.recv_multipart()
                msg = p.decode(frames, synth.format)  # poses and the onsets the synth forwards
                msgs.append((msg.seq, b"".join(frames)))
            got.append(msgs)
    finally:
        codes = [stop(proc) for proc in procs]
        stop_synth.set()
        thread.join(5)
        for s in subs:
            s.close(0)
        pub.close(0)
        ctx.term()
    direct = got[0]
    assert len(direct) > 50, "the synth published too few messages to judge"
    kinds = [{frames[5] for _, frames in msgs} for msgs in got]  # the header's kind byte
    assert all({p.Kind.POSE, p.Kind.SHOWN_ONSET, p.Kind.SHOWN_CONTROL} <= k for k in kinds)
    assert [seq for seq, _ in direct] == list(range(direct[0][0], direct[0][0] + len(direct)))
    # The synth publishes from its start (the idle drummer too): a subscriber behind a relay
    # joins a few messages later, once its subscription has climbed the tree; from then on it
    # must hold every message, byte for byte, and it must have joined before the music began.
    for k, msgs in enumerate(got[1:], 1):
        joined = msgs[0][0] - direct[0][0]
        assert 0 <= joined < 60, f"subscriber {k} joined {joined} messages late"
        assert msgs == direct[joined:], f"subscriber {k} ({where[k]}) got other messages"
    assert codes == [0, 0]
    summary = (tmp_path / "relay2.err").read_text()
    # the second relay forwarded exactly what its first subscriber received
    assert f"relay: {max(len(got[4]), len(got[5]))} messages" in summary, summary


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["--upstream", "nowhere"], "upstream endpoint: 'nowhere' is not a ZeroMQ endpoint"),
     (["--upstream", "tcp://127.0.0.1:5720", "--pub", "tcp://10.1.2.3:5820"],
      "refusing to bind tcp://10.1.2.3:5820 without CURVE")],
)  # fmt: skip
def test_bad_relay_options_are_one_line(tmp_path: Path, argv: list[str], message: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "services", "relay", *argv],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert done.returncode == 2
    assert message in done.stderr and done.stderr.count("\n") == 1, done.stderr
