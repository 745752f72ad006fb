"""Hardening: kill -9 each stage of a live session; unplug and replug devices; CURVE under ``up``.

The session is the real launcher, ``livedrummer up --serial PTY``, fed numbered notes on a
pseudo-terminal by :class:`services.bench._faultrig.Rig` (every note is a unique (note, velocity) pair,
so an onset on the bus or in the journal names the note written). What "lost no onset" means
here, precisely:

* *acknowledged* onsets are those the input daemon published (seen by our own subscriber on
  its stream); the daemon journals each batch before publishing it, so every acknowledged
  onset must be in the journal, whichever daemon process published it;
* every note written while a daemon process was serving and given time to arrive (we stop
  writing and wait before each kill) must be acknowledged, so in the journal too;
* notes written while the input daemon was dead go to a pty nobody has open; the new daemon
  flushes the tty's input when it opens the device (pyserial does, like a real port that
  was unplugged), so those may be lost. We assert nothing about them beyond the journal
  holding only notes that were written, each once, in the order written.

Bounds are generous (a loaded 2-core machine); the recovery figures are in
``livedrummer bench recovery``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import zmq

from livedrummer import protocol as p
from services.bench._faultrig import INDEX, REPO, Rig
from services.bench._ports import free_port_base
from services.cli import main
from services.input.journal import list_sessions, load_journal
from services.process.supervisor import ServiceSpec, Supervisor
from services.wire.net import Security, connect

REFUSED_WAIT_MS = 1000


def port_base() -> int:
    return free_port_base()


def journal_indices(home: Path) -> tuple[list[int], list[bool]]:
    """Note indices of every journaled onset, sessions in time order; and each one's clean flag."""
    loaded = [load_journal(s.path) for s in list_sessions(home / "sessions")]
    loaded.sort(key=lambda j: float(j.onsets["time_s"][0]) if j.onsets.size else 0.0)
    out = [INDEX[(int(r["note"]), int(r["velocity"]))] for j in loaded for r in j.onsets]
    return out, [j.clean for j in loaded]


def test_kill_each_stage_in_turn_while_notes_flow(gl_ok: None, tmp_path: Path) -> None:
    t_start = time.monotonic()
    with Rig(tmp_path, port_base()) as rig:
        rig.start()
        pids = rig.pids()
        assert set(pids) == {"input", "synth", "display"}, pids
        # Warm: notes reach the bus, the synth lights the pieces, the display draws poses.
        assert rig.pump(lambda: len(rig.bus) >= 20 and rig.glow_after(0.0) > 0.3, 20)
        assert rig.pump(lambda: any(f["pose_s"] for f in rig.frames()), 10)

        # ---- input daemon --------------------------------------------------------------
        assert rig.settle(), "notes written while the daemon served did not all arrive"
        acked_before = len(rig.written)
        last_before = max(t for _, t in rig.bus)
        rec = rig.kill("input")
        recoveries = [rec]
        assert rec.new_pid != pids["input"]
        now = rig.pids()
        assert now == {**pids, "input": rec.new_pid}, (pids, now)  # the others kept running
        # The synth takes onsets from the new daemon (it missed the new stream's first numbers).
        assert rig.pump(lambda: any(t > last_before + 1.0 for _, t in rig.bus), 15)
        first_new = min(t for _, t in rig.bus if t > last_before + 1.0)
        assert rig.pump(lambda: rig.glow_after(first_new) > 0.3, 10), (
            "the synth got no onset from the restarted input daemon:\n" + rig.output()[-2000:]
        )
        pids = now

        # ---- synth: the display holds the last pose, then resumes ------------------------
        assert rig.pump(lambda: rig.newest_pose_s() > time.monotonic() - 0.1, 5)
        rec = rig.kill("synth")
        recoveries.append(rec)
        now = rig.pids()
        assert now == {**pids, "synth": rec.new_pid} and rec.new_pid != pids["synth"], now
        frames = rig.frames()
        held = [f for f in frames if rec.killed_at + 0.2 < f["render_s"] < rec.ready_at]
        assert len(held) >= 3, "the display stopped drawing while the synth was down"
        stale = held[0]["newest_s"]
        # The new synth says it is ready once it has published its first poses, so a frame or
        # two before its ready line is read may already show them; any other newest pose than
        # the dead synth's last one must be the new synth's (well after the kill: a synth
        # publishes at most D = 30 ms ahead).
        fresh = [f["newest_s"] for f in held if f["newest_s"] != stale]
        assert all(s > rec.killed_at + 0.2 for s in fresh), "poses arrived from a dead synth?"
        assert len(held) - len(fresh) >= 3, "the display stopped drawing while the synth was down"
        assert all(f["pose_s"] is not None for f in held), "the held pose was dropped"
        assert rig.pump(lambda: any(f["newest_s"] > stale + 0.5 for f in rig.frames()), 15), (
            "the display never got poses from the restarted synth"
        )
        resumed = rig.pump(lambda: rig.glow_after(rec.ready_at) > 0.3, 10)
        assert resumed, "the restarted synth does not turn onsets into hits"
        pids = now

        # ---- display ----------------------------------------------------------------------
        before = len(rig.frames())
        rec = rig.kill("display")
        recoveries.append(rec)
        now = rig.pids()
        assert now == {**pids, "display": rec.new_pid} and rec.new_pid != pids["display"], now
        assert rig.pump(
            lambda: (
                sum(1 for f in rig.frames() if f["pose_s"] and f["render_s"] > rec.ready_at) >= 10
            ),
            15,
        ), f"the new display draws no poses (had {before} frames)"

        first_after = min(i for i, _ in rig.bus if i >= acked_before)
        assert rig.settle(first_after), "notes written after the restarts did not all arrive"
        out = rig.stop()
    assert "up: stopped (3 restarts)" in out, out[-2000:]
    print("death to ready:", ", ".join(f"{r.name} {r.ready_after_s:.2f} s" for r in recoveries))

    journal, clean = journal_indices(tmp_path / "home")
    assert clean == [False, True], clean  # the killed daemon's journal, then the clean one
    written = [i for i, _ in rig.written]
    bus = [i for i, _ in rig.bus]
    assert len(journal) == len(set(journal)), "an onset journaled twice"
    assert journal == sorted(journal) and set(journal) <= set(written)
    assert set(bus) <= set(journal), sorted(set(bus) - set(journal))[:20]
    # Every note written while a daemon served and was given time is in the journal:
    # before the kill, and everything from the first note the new daemon published on.
    served = set(written[:acked_before]) | {i for i in written if i >= first_after}
    assert served <= set(journal), sorted(served - set(journal))[:20]
    lost = sorted(set(written) - set(journal))
    assert all(acked_before <= i < first_after for i in lost), lost  # only during the outage
    assert time.monotonic() - t_start < 90


def test_serial_replug_reconnects_and_publishes_within_bounds(tmp_path: Path) -> None:
    """Close the pty (unplug), open a new one under the same path (replug): notes flow again."""
    from services.bench.recovery import serial_replug

    took = serial_replug(tmp_path)
    assert took < 3.0, f"first note {took:.3f} s after the replug"


def test_jack_port_removed_and_recreated_reconnects(jack_server: str, tmp_path: Path) -> None:
    from services.bench.recovery import jack_replug

    took = jack_replug(tmp_path)
    assert took < 3.0, f"first note {took:.3f} s after the port came back"


def test_up_over_curve_renders_and_refuses_a_stranger(gl_ok: None, tmp_path: Path) -> None:
    keys = tmp_path / "keys"
    for name in ("rig", "friend", "stranger"):
        assert main(["keys", "new", name, "--keys-dir", str(keys)]) == 0
    allow = tmp_path / "allow"
    allow.mkdir()
    for name in ("rig", "friend"):
        (allow / f"{name}.key").write_bytes((keys / f"{name}.key").read_bytes())
    base = port_base()
    curve = ["--curve-secret", str(keys / "rig.key_secret"), "--allow", str(allow)]
    with Rig(tmp_path, base, extra=curve) as rig:
        rig.start()
        ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
        try:
            subs = {}
            for name in ("friend", "stranger"):
                sock = ctx.socket(zmq.SUB)
                sock.setsockopt(zmq.LINGER, 0)
                sock.setsockopt(zmq.SUBSCRIBE, b"")
                sec = Security.from_files(
                    secret=keys / f"{name}.key_secret", server_key=keys / "rig.key"
                )
                connect(sock, f"tcp://127.0.0.1:{base + 10}", "test sub", sec)
                subs[name] = sock
            plain = ctx.socket(zmq.SUB)
            plain.setsockopt(zmq.LINGER, 0)
            plain.setsockopt(zmq.SUBSCRIBE, b"")
            plain.connect(f"tcp://127.0.0.1:{base + 10}")
            subs["plain"] = plain
            got = dict.fromkeys(subs, 0)
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline and not (
                got["friend"] >= 20 and any(f["pose_s"] for f in rig.frames())
            ):
                rig.write_note()
                for name, sock in subs.items():
                    while sock.poll(10):
                        msg = p.decode(sock.recv_multipart(), rig.format)
                        got[name] += msg.kind is p.Kind.POSE
            for name in ("stranger", "plain"):  # a last chance for the refused ones
                if subs[name].poll(REFUSED_WAIT_MS):
                    got[name] += 1
            drawn = [f for f in rig.frames() if f["pose_s"] is not None]
        finally:
            for sock in subs.values():
                sock.close(0)
            ctx.term()
        out = rig.stop()
    assert got["friend"] >= 20, (got, out[-2000:])
    assert got["stranger"] == 0 and got["plain"] == 0, got
    assert len(drawn) >= 10, out[-2000:]  # the rig's own display is served over CURVE
    assert "input ready again" not in out  # nothing crashed


def test_up_refuses_an_allow_folder_without_its_own_key(tmp_path: Path) -> None:
    keys = tmp_path / "keys"
    for name in ("rig", "friend"):
        assert main(["keys", "new", name, "--keys-dir", str(keys)]) == 0
    allow = tmp_path / "allow"
    allow.mkdir()
    (allow / "friend.key").write_bytes((keys / "friend.key").read_bytes())
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--seconds",
            "1",
            "--curve-secret",
            str(keys / "rig.key_secret"),
            "--allow",
            str(allow),
        ],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=REPO,
        env={**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")},
    )
    assert proc.returncode == 2, proc.stderr
    assert "lacks this rig's public key" in proc.stderr and str(allow) in proc.stderr


def test_a_restart_waits_for_its_back_off_only_and_is_timed(tmp_path: Path) -> None:
    """``run_once(long)`` must still restart on time: the back-off, not the poll timeout."""
    code = "import time\nfrom services.process.notify import ready\nready('up')\ntime.sleep(120)\n"
    spec = ServiceSpec("svc", [sys.executable, "-c", code], env={"PYTHONPATH": str(REPO)})
    sup = Supervisor([spec])
    try:
        sup.start()
        old = sup.pid("svc")
        assert old is not None
        os.kill(old, signal.SIGKILL)
        t0 = time.monotonic()
        while not (sup.is_ready("svc") and sup.pid("svc") != old):
            assert time.monotonic() - t0 < 15, "not restarted"
            sup.run_once(20.0)  # longer than the whole bound: each call must end at the restart
        assert sup.restarts["svc"] == 1
        assert len(sup.recoveries["svc"]) == 1
        assert 0.1 <= sup.recoveries["svc"][0] < 15  # at least the first back-off
    finally:
        sup.stop()
