"""The avatar on the wire: its digest in HELLO/READY, the synth announcing it, a display comparing.

Round trips of the Hello JSON with and without the ``avatar`` key (a peer from before it is
still read), its checks, and a real ``synth --avatar`` process whose READY carries the digest
that a display started with another avatar warns about in one line.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import avatar_files as af
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.avatar.loader import load_avatar_file
from services.display.avatar_check import avatar_mismatch, check_synth_avatar
from services.wire.net import request_ready

LOCAL = "tcp://127.0.0.1:*"
DIGEST = "0123456789abcdef"


def test_hello_keys_table_is_what_is_written() -> None:
    obj = json.loads(p.Hello("synth", "poses", avatar=DIGEST).to_bytes())
    assert set(obj) == set(p.HELLO_KEYS)
    assert obj["avatar"] == DIGEST


def test_hello_round_trips_the_avatar() -> None:
    hello = p.Hello("synth", "poses", 7, {"pub": "tcp://127.0.0.1:5"}, avatar=DIGEST)
    for kind in (p.Kind.HELLO, p.Kind.READY):
        back = p.decode(p.encode(p.Message(kind, hello, stream=p.Stream.CONTROL)))
        assert back.body == hello
    built_in = p.Hello("display", "frames")
    assert p.Hello.from_bytes(built_in.to_bytes()) == built_in and built_in.avatar == ""


def test_hello_without_avatar_is_read_and_bad_ones_named() -> None:
    obj = json.loads(p.Hello("input", "source").to_bytes())
    del obj["avatar"]  # a peer from before the key
    assert p.Hello.from_bytes(json.dumps(obj).encode()).avatar == ""
    for bad in ("xyz", "0123456789ABCDEF", 12, "0" * 17):
        obj["avatar"] = bad
        with pytest.raises(p.WireError) as exc:
            p.Hello.from_bytes(json.dumps(obj).encode())
        assert exc.value.field == "hello.avatar"
    obj["avatar"] = ""
    obj["avatars"] = ""
    with pytest.raises(p.WireError, match="expected keys"):
        p.Hello.from_bytes(json.dumps(obj).encode())


def test_mismatch_is_one_line_naming_both(tmp_path: Path) -> None:
    a = load_avatar_file(af.write(tmp_path, "vrm1.vrm"))
    assert avatar_mismatch(a, a.digest) is None
    assert avatar_mismatch(None, "") is None
    line = avatar_mismatch(None, a.digest)
    assert line is not None and "\n" not in line
    assert "built-in character" in line and a.digest in line


def test_synth_announces_its_avatar_in_ready(tmp_path: Path) -> None:
    path = af.write(tmp_path, "tall.glb")
    avatar = load_avatar_file(path)
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
            "--avatar",
            str(path),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = json.loads(proc.stdout.readline())
        ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        try:
            ready = request_ready(ctx, line["control"], p.Hello("test", "probe"), 10.0)
            assert ready.avatar == avatar.digest
            assert check_synth_avatar(ctx, line["control"], avatar) is None
            warning = check_synth_avatar(ctx, line["control"], None)
        finally:
            ctx.term()
        assert warning is not None and avatar.digest in warning
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
