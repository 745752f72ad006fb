"""Security of remote streams: CURVE key files, authenticated streams, refused peers.

Real sockets over TCP on 127.0.0.1 with OS-chosen ports. A stream that carries onsets is
started once per test; an allowed client must receive them while, in the same window, a
client with an unlisted key and a plain (non-CURVE) client receive nothing. The negative
checks wait a bounded time (1 s) *after* the allowed client has already been served, so a
broken authenticator fails them instead of passing by slowness.
"""

from __future__ import annotations

import ast
import logging
import math
import os
import stat
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import zmq
import zmq.auth

from livedrummer import protocol as p
from livedrummer.errors import KeyFileError, ProtocolError
from livedrummer.kit.vocabulary import HiHat, Zone
from livedrummer.protocol.keys import format_key_file, parse_key_file, read_key_file
from livedrummer.timeline.clock import MonotonicClock
from livedrummer.timeline.events import Onset
from services.cli import main
from services.input.base import Event, Source
from services.input.daemon import DaemonConfig, InputDaemon
from services.input.remote import RemoteSource
from services.wire.net import Security, bind, connect, is_loopback, load_secret, request_ready

REPO = Path(__file__).resolve().parents[3]
LOCAL = "tcp://127.0.0.1:*"
REFUSED_WAIT_MS = 1000


@pytest.fixture
def ctx() -> Iterator[zmq.Context[zmq.Socket[bytes]]]:
    c: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    yield c
    c.destroy(linger=0)


def make_keys(folder: Path, name: str) -> Path:
    """``livedrummer keys new NAME --keys-dir folder``; returns the secret file."""
    assert main(["keys", "new", name, "--keys-dir", str(folder)]) == 0
    return folder / f"{name}.key_secret"


class SnareSource(Source):
    """A source that yields one snare onset every few milliseconds, forever."""

    def open(self) -> None:
        self.is_open = True

    def read(self, timeout_s: float) -> list[Event]:
        time.sleep(min(timeout_s, 0.005))
        return [Onset(self.clock.now(), 38, 100, 9, "snare", Zone.HEAD, HiHat.NONE, math.nan)]

    def close(self) -> None:
        self.is_open = False


@pytest.fixture
def site(tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]) -> Iterator[tuple[InputDaemon, Path]]:
    """A daemon serving CURVE with an allow folder holding only ``friend``'s public key."""
    keys = tmp_path / "keys"
    server_secret = make_keys(keys, "server")
    make_keys(keys, "friend")
    make_keys(keys, "stranger")
    allow = tmp_path / "allow"
    allow.mkdir()
    (allow / "friend.key").write_bytes((keys / "friend.key").read_bytes())
    clock = MonotonicClock()
    config = DaemonConfig(
        pub=LOCAL,
        control=LOCAL,
        journal=False,
        security=Security.from_files(secret=server_secret, allow=allow),
    )
    daemon = InputDaemon(SnareSource("snare", clock), config, clock, ctx)
    daemon.start()
    stop = threading.Event()
    thread = threading.Thread(target=daemon.run, args=(stop,), daemon=True)
    thread.start()
    try:
        yield daemon, keys
    finally:
        stop.set()
        thread.join(5)


def client(keys: Path, name: str) -> Security:
    return Security.from_files(secret=keys / f"{name}.key_secret", server_key=keys / "server.key")


def raw_sub(
    ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str, security: Security | None
) -> zmq.Socket[bytes]:
    sock = ctx.socket(zmq.SUB)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.SUBSCRIBE, b"")
    connect(sock, endpoint, "test sub", security)
    return sock


def first_onsets(src: RemoteSource, want: int, timeout_s: float = 10.0) -> list[Onset]:
    got: list[Onset] = []
    deadline = time.monotonic() + timeout_s
    while len(got) < want and time.monotonic() < deadline:
        got.extend(e for e in src.read(0.05) if isinstance(e, Onset))
    return got


# ---------------------------------------------------------------- authenticated streams


def test_allowed_client_is_served_and_others_get_nothing(
    site: tuple[InputDaemon, Path],
    ctx: zmq.Context[zmq.Socket[bytes]],
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.DEBUG, logger="livedrummer.auth")
    daemon, keys = site
    pub = daemon.endpoints["pub"]
    stranger = raw_sub(ctx, pub, client(keys, "stranger"))
    plain = raw_sub(ctx, pub, None)
    friend = RemoteSource(pub, MonotonicClock(), ctx, security=client(keys, "friend"))
    friend.open()
    try:
        got = first_onsets(friend, 5)
        assert len(got) >= 5
        assert all(o.note == 38 and o.instrument == "snare" for o in got)
        # The stream is flowing (the friend was just served); the others still get nothing.
        assert not stranger.poll(REFUSED_WAIT_MS)
        assert not plain.poll(REFUSED_WAIT_MS // 2)
        assert friend.problems.summary() == {}
    finally:
        friend.close()
        stranger.close(0)
        plain.close(0)
    denied = [r.getMessage() for r in caplog.records if r.name == "livedrummer.auth"]
    assert any(m.startswith("DENIED") for m in denied), denied
    assert any(m.startswith("ALLOWED") for m in denied), denied


def test_hello_on_the_curve_control_socket(
    site: tuple[InputDaemon, Path], ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    daemon, keys = site
    control = daemon.endpoints["control"]
    ready = request_ready(ctx, control, p.Hello("test", "sink"), 10.0, client(keys, "friend"))
    assert ready.service == "input" and ready.endpoints["pub"] == daemon.endpoints["pub"]
    with pytest.raises(ProtocolError, match="no READY"):
        request_ready(ctx, control, p.Hello("test", "sink"), 1.0, client(keys, "stranger"))
    with pytest.raises(ProtocolError, match="no READY"):
        request_ready(ctx, control, p.Hello("test", "sink"), 0.5)


def test_client_with_the_wrong_server_key_gets_nothing(
    site: tuple[InputDaemon, Path], ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    daemon, keys = site
    wrong = Security.from_files(secret=keys / "friend.key_secret", server_key=keys / "stranger.key")
    sock = raw_sub(ctx, daemon.endpoints["pub"], wrong)
    right = raw_sub(ctx, daemon.endpoints["pub"], client(keys, "friend"))
    try:
        assert right.poll(10_000)  # served with the right server key
        assert not sock.poll(REFUSED_WAIT_MS)
    finally:
        sock.close(0)
        right.close(0)


# ---------------------------------------------------------------- binding


def test_non_loopback_bind_without_curve_is_refused(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    for endpoint in ("tcp://0.0.0.0:*", "tcp://*:*", "tcp://192.168.1.10:5710"):
        sock = ctx.socket(zmq.PUB)
        try:
            with pytest.raises(ProtocolError, match=r"refusing to bind .* without CURVE"):
                bind(sock, endpoint, "pub endpoint")
        finally:
            sock.close(0)
    clock = MonotonicClock()
    config = DaemonConfig(pub="tcp://0.0.0.0:*", control=LOCAL, journal=False)
    daemon = InputDaemon(SnareSource("snare", clock), config, clock, ctx)
    with pytest.raises(ProtocolError, match="--curve-secret"):
        daemon.start()


def test_cli_refuses_a_public_bind_in_one_line(tmp_path: Path) -> None:
    groove = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"
    if not groove.exists():
        from services.cli.files import demo_groove

        groove = demo_groove()
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--file",
            str(groove),
            "--no-journal",
            "--pub",
            "tcp://0.0.0.0:*",
            "--control",
            LOCAL,
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
        env={**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")},
    )
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "refusing to bind tcp://0.0.0.0:*" in lines[0], proc.stderr


def test_loopback_table() -> None:
    for local in ("tcp://127.0.0.1:5", "tcp://127.1.2.3:*", "tcp://localhost:9", "ipc:///x"):
        assert is_loopback(local), local
    for remote in ("tcp://0.0.0.0:5", "tcp://*:5", "tcp://10.0.0.1:5", "tcp://eth0:5"):
        assert not is_loopback(remote), remote


# ---------------------------------------------------------------- key files


def test_keys_new_round_trips_and_pyzmq_reads_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    secret_path = make_keys(tmp_path, "alice")
    public_path = tmp_path / "alice.key"
    assert stat.S_IMODE(secret_path.stat().st_mode) == 0o600
    pair = load_secret(secret_path)
    assert pair.secret is not None and zmq.curve_public(pair.secret) == pair.public
    assert read_key_file(public_path, secret=False).public == pair.public
    assert read_key_file(public_path, secret=False).secret is None
    assert zmq.auth.load_certificate(secret_path) == (pair.public, pair.secret)
    assert zmq.auth.load_certificate(public_path) == (pair.public, None)
    text = format_key_file("alice", pair.public, pair.secret)
    assert parse_key_file(text, "x") == pair
    assert pair.public.decode() in capsys.readouterr().out
    # never overwritten, and listed
    assert main(["keys", "new", "alice", "--keys-dir", str(tmp_path)]) == 2
    assert "already exists" in capsys.readouterr().err
    assert load_secret(secret_path) == pair
    assert main(["keys", "list", "--keys-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "alice" in out and pair.public.decode() in out and "+ secret" in out


def test_default_key_folder_is_under_livedrummer_home(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("LIVEDRUMMER_HOME", str(tmp_path))
    assert main(["keys", "new", "bob"]) == 0
    assert (tmp_path / "keys" / "bob.key").is_file()
    assert (tmp_path / "keys" / "bob.key_secret").is_file()


@pytest.mark.parametrize(
    ("content", "match"),
    [
        (b"", "no public-key"),
        (b'curve\n    public-key = "short"\n', "not a 40-character Z85 key"),
        (b"import os\n", "unexpected line"),
        (b"\x80\x81 binary", "non-ASCII"),
        (b'curve\n    public-key = "' + b"~" * 40 + b'"\n', "Z85"),
    ],
)
def test_corrupt_key_file_is_one_named_line(
    tmp_path: Path, content: bytes, match: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.key_secret"
    path.write_bytes(content)
    with pytest.raises(KeyFileError, match=match) as info:
        load_secret(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)
    code = main(
        [
            "input",
            "--remote",
            LOCAL.replace("*", "1"),
            "--curve-secret",
            str(path),
            "--server-key",
            str(path),
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and str(path) in err[0]


def test_secret_must_match_its_public_key_and_be_a_secret(tmp_path: Path) -> None:
    a, b = make_keys(tmp_path, "a"), make_keys(tmp_path, "b")
    pa, pb = load_secret(a), load_secret(b)
    assert pa.secret is not None
    mixed = tmp_path / "mixed.key_secret"
    mixed.write_text(format_key_file("mixed", pb.public, pa.secret))
    with pytest.raises(KeyFileError, match="does not belong"):
        load_secret(mixed)
    with pytest.raises(KeyFileError, match="no secret-key"):
        load_secret(tmp_path / "a.key")
    with pytest.raises(KeyFileError, match="cannot read"):
        load_secret(tmp_path / "missing.key_secret")
    with pytest.raises(KeyFileError, match="key name"):
        format_key_file("../evil", pa.public)


# ---------------------------------------------------------------- no pickle, no eval


BANNED_MODULES = {"pickle", "cPickle", "_pickle", "marshal", "shelve", "dill", "cloudpickle"}


def banned_uses(source: str, where: str) -> list[str]:
    """Imports of pickle-like modules, eval/exec calls and ``allow_pickle`` in ``source``."""
    found: list[str] = []
    for node in ast.walk(ast.parse(source, where)):
        line = getattr(node, "lineno", 0)
        if isinstance(node, ast.Import):
            names = [a.name.split(".")[0] for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [(node.module or "").split(".")[0]]
        else:
            names = []
        found += [f"{where}:{line}: import {n}" for n in names if n in BANNED_MODULES]
        if isinstance(node, ast.Call):
            func = node.func
            name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
            if name in ("eval", "exec", "__import__"):
                found.append(f"{where}:{line}: {name}()")
            for kw in node.keywords:
                if kw.arg == "allow_pickle" and not (
                    isinstance(kw.value, ast.Constant) and kw.value.value is False
                ):
                    found.append(f"{where}:{line}: allow_pickle")
    return found


def test_the_scanner_finds_what_it_bans() -> None:
    bad = (
        "import pickle\nfrom marshal import loads\nimport os.path\n"
        "eval('1')\nbuiltins.exec('x')\nnp.load(f, allow_pickle=True)\nnp.load(f, allow_pickle=False)\n"
    )
    assert [h.split(": ")[1] for h in banned_uses(bad, "x")] == [
        "import pickle",
        "import marshal",
        "eval()",
        "exec()",
        "allow_pickle",
    ]


#: Modules that pickle only to processes they start themselves, over a pipe or socket pair
#: made before the child exists (the render's frame workers, the synth's curve worker): no
#: one else can write into it. They may import pickle and nothing that reaches a network.
PRIVATE_PIPES = {
    "services/display/parallel.py": ("import pickle",),
    "services/synth/curveworker.py": ("import pickle",),
}


def test_no_pickle_eval_or_exec_in_the_code() -> None:
    """Nothing that reads a socket or a file may unpickle or evaluate what it read."""
    files = [f for d in ("livedrummer", "services") for f in sorted((REPO / d).rglob("*.py"))]
    assert len(files) > 20
    found: list[str] = []
    for path in files:
        where = str(path.relative_to(REPO))
        uses = banned_uses(path.read_text(encoding="utf-8"), where)
        allowed = PRIVATE_PIPES.get(where, ())
        found += [u for u in uses if u.split(": ", 1)[1] not in allowed]
    assert found == []
    for where in PRIVATE_PIPES:  # a private pipe stays private: no network in those modules
        tree = ast.parse((REPO / where).read_text(encoding="utf-8"))
        names = {
            a.name.split(".")[0]
            for n in ast.walk(tree)
            if isinstance(n, ast.Import)
            for a in n.names
        } | {
            (n.module or "").split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
        }
        assert not names & {"zmq", "http", "urllib", "asyncio"}, where
        calls = {
            n.func.attr
            for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
        }
        assert not calls & {"bind", "listen", "connect", "accept"}, where


# ---------------------------------------------------------------- the real commands


def test_cli_remote_jam_over_curve(tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]) -> None:
    """Site A serves a file over CURVE to site B only; B relays it on its own stream."""
    import json

    keys = tmp_path / "keys"
    a_secret, b_secret = make_keys(keys, "siteA"), make_keys(keys, "siteB")
    allow = tmp_path / "allow"
    allow.mkdir()
    (allow / "siteB.key").write_bytes((keys / "siteB.key").read_bytes())
    groove = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    common = ["--pub", LOCAL, "--control", LOCAL, "--no-journal"]
    procs: list[subprocess.Popen[str]] = []

    def start(*args: str) -> dict[str, str]:
        proc = subprocess.Popen(
            [sys.executable, "-m", "services", "input", *args, *common],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
            env=env,
        )
        procs.append(proc)
        assert proc.stdout is not None
        info: dict[str, str] = json.loads(proc.stdout.readline())
        return info

    try:
        a = start(
            "--file",
            str(groove),
            "--loop",
            "--map",
            "roland-td",
            "--curve-secret",
            str(a_secret),
            "--allow",
            str(allow),
        )
        b = start(
            "--remote",
            a["pub"],
            "--curve-secret",
            str(b_secret),
            "--server-key",
            str(keys / "siteA.key"),
        )
        # B's own stream is CURVE too (one --curve-secret serves all of B's sockets); no
        # --allow on B, so any client that knows B's public key may read it.
        reader = Security.from_files(secret=a_secret, server_key=keys / "siteB.key")
        local = raw_sub(ctx, b["pub"], reader)
        deadline = time.monotonic() + 20.0
        onsets = 0
        while onsets < 3 and time.monotonic() < deadline:
            if local.poll(100):
                msg = p.decode(local.recv_multipart())
                if msg.kind is p.Kind.ONSET:
                    assert msg.flags & p.Flag.RELAYED
                    onsets += msg.rows.size
        local.close(0)
        assert onsets >= 3
    finally:
        for proc in procs:
            proc.terminate()
        for proc in procs:
            proc.communicate(timeout=10)
