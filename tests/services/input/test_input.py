"""Input daemon with real parts: ZeroMQ sockets, pseudo-terminals, subprocesses, journals."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import mido
import numpy as np
import pytest
import zmq

from livedrummer import protocol as p
from livedrummer.errors import MidiInputError, ProtocolError
from livedrummer.midi.decode import MessageDecoder
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import MonotonicClock, SteppedClock
from livedrummer.timeline.events import Control, ControlKind, Onset
from services.input.base import RawMidi
from services.input.daemon import DaemonConfig, InputDaemon
from services.input.fileplayer import FileSource
from services.input.journal import load_journal
from services.input.midiport import choose_port
from services.input.remote import RemoteSource
from services.input.serialport import SerialSource
from services.wire.net import check_endpoint, request_ready

REPO = Path(__file__).resolve().parents[3]
ROLAND = load_note_map("roland-td")
LOCAL = "tcp://127.0.0.1:*"


@pytest.fixture
def ctx() -> Iterator[zmq.Context[zmq.Socket[bytes]]]:
    c: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    yield c
    c.destroy(linger=0)


def short_groove(path: Path, notes: int = 120, step_ticks: int = 30) -> Path:
    """A ~1 s file at 480 tpb / 120 bpm: kick, snare, hi-hat with CC4, a choke, a duplicate."""
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    cycle = [36, 38, 42, 46, 49]
    for i in range(notes):
        note = cycle[i % len(cycle)]
        if note in (42, 46):
            track.append(
                mido.Message("control_change", channel=9, control=4, value=(i * 7) % 128, time=0)
            )
        track.append(
            mido.Message(
                "note_on", channel=9, note=note, velocity=1 + i % 127, time=step_ticks if i else 0
            )
        )
        if note == 49:
            track.append(mido.Message("polytouch", channel=9, note=49, value=127, time=0))
        track.append(mido.Message("note_on", channel=9, note=note, velocity=0, time=1))
    track.append(mido.Message("note_on", channel=9, note=99, velocity=50, time=5))  # not in the map
    mid.tracks.append(track)
    mid.save(path)
    return path


def expected_events(path: Path) -> tuple[np.ndarray, np.ndarray]:
    perf = read_midi_file(path, ROLAND)
    return perf.onsets, perf.controls


class Subscriber:
    """Collects decoded messages from a SUB socket, tracking sequence numbers."""

    def __init__(self, ctx: zmq.Context[zmq.Socket[bytes]], endpoint: str) -> None:
        self.sock = ctx.socket(zmq.SUB)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.setsockopt(zmq.SUBSCRIBE, b"")
        self.sock.connect(endpoint)
        self.messages: list[p.Message] = []
        self.tracker = p.SequenceTracker()
        self.reports: list[p.SeqReport] = []

    def collect(self, until: Any, timeout_s: float = 20.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not until(self) and time.monotonic() < deadline:
            if self.sock.poll(50):
                msg = p.decode(self.sock.recv_multipart())
                self.reports.append(self.tracker.observe_message(msg))
                self.messages.append(msg)

    def rows(self, kind: p.Kind) -> np.ndarray:
        parts = [m.rows for m in self.messages if m.kind is kind]
        dtype = p.SPECS[kind].rows
        return np.concatenate(parts) if parts else np.zeros(0, dtype)

    def count(self, kind: p.Kind) -> int:
        return int(self.rows(kind).size)


def start_daemon(
    source: Any, clock: Any, ctx: zmq.Context[zmq.Socket[bytes]], tmp_path: Path, **cfg: Any
) -> tuple[InputDaemon, threading.Thread, threading.Event]:
    config = DaemonConfig(pub=LOCAL, control=LOCAL, sessions_dir=tmp_path / "sessions", **cfg)
    daemon = InputDaemon(source, config, clock, ctx)
    daemon.start()
    stop = threading.Event()
    thread = threading.Thread(target=daemon.run, args=(stop,), daemon=True)
    thread.start()
    return daemon, thread, stop


def assert_contiguous(sub: Subscriber) -> None:
    seqs = [m.seq for m in sub.messages]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
    assert sub.reports[0].status is p.SeqStatus.FIRST
    assert all(r.status is p.SeqStatus.OK for r in sub.reports[1:])


# ---------------------------------------------------------------- small parts


def test_raw_midi_from_bytes_matches_mido_fields() -> None:
    for raw in ([0x99, 38, 100], [0xB9, 4, 90], [0xA9, 49, 127], [0x89, 38, 0], [0xC9, 5]):
        ours = RawMidi.from_bytes(raw[0], bytes(raw[1:]))
        ref = mido.Message.from_bytes(raw)
        assert ours is not None and ours.type == ref.type and ours.channel == ref.channel
        for name in ("note", "velocity", "control", "value"):
            if hasattr(ref, name):
                assert getattr(ours, name) == getattr(ref, name), (raw, name)
    assert RawMidi.from_bytes(0xF8, b"") is None
    assert RawMidi.from_bytes(0x99, b"\x26") is None


def test_choose_port_by_name_or_unique_substring() -> None:
    ports = [
        "Midi Through:Midi Through Port-0 14:0",
        "TD-17:TD-17 MIDI 1 20:0",
        "TD-27:TD-27 MIDI 1 24:0",
    ]
    assert choose_port("TD-17:TD-17 MIDI 1 20:0", ports) == 1
    assert choose_port("td-27", ports) == 2
    with pytest.raises(MidiInputError, match="several"):
        choose_port("TD-", ports)
    with pytest.raises(MidiInputError, match="not found"):
        choose_port("Nitro", ports)


def test_endpoints_are_checked() -> None:
    assert check_endpoint("tcp://127.0.0.1:*") == "tcp://127.0.0.1:*"
    for bad in ("127.0.0.1:5", "tcp://127.0.0.1", "tcp://127.0.0.1:70000", "udp://x:1", ""):
        with pytest.raises(ProtocolError, match="endpoint"):
            check_endpoint(bad)


def test_file_source_releases_events_at_their_times(tmp_path: Path) -> None:
    path = short_groove(tmp_path / "g.mid")
    onsets, controls = expected_events(path)
    clock = SteppedClock(50.0)
    src = FileSource(path, clock, ROLAND, performer=3)
    src.open()
    got: list[Any] = []
    while not src.finished():
        got.extend(src.read(0.5))
    got_on = [e for e in got if isinstance(e, Onset)]
    got_ctl = [e for e in got if isinstance(e, Control)]
    assert [o.note for o in got_on] == onsets["note"].tolist()
    assert [o.velocity for o in got_on] == onsets["velocity"].tolist()
    assert [o.time_s for o in got_on] == pytest.approx((50.0 + onsets["time_s"]).tolist())
    assert [c.value for c in got_ctl] == controls["value"].tolist()
    assert all(o.source == 3 for o in got_on)
    times = [e.time_s for e in got]
    assert times == sorted(times)
    # CC4 precedes the hi-hat note it belongs to.
    i = next(k for k, e in enumerate(got) if isinstance(e, Onset) and e.note == 42)
    assert isinstance(got[i - 1], Control) and got[i - 1].kind is ControlKind.HIHAT_PEDAL


# ---------------------------------------------------------------- daemon in process


def test_daemon_publishes_every_event_in_order_and_journals_them(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    path = short_groove(tmp_path / "g.mid", notes=300)
    onsets, controls = expected_events(path)
    clock = SteppedClock(1000.0)
    src = FileSource(path, clock, ROLAND, performer=5)
    daemon, thread, _stop = start_daemon(
        src, clock, ctx, tmp_path, performer=5, wait_subscribers=1, exit_at_end=True
    )
    ready = request_ready(ctx, daemon.endpoints["control"], p.Hello("test", "sink"), 5.0)
    assert (ready.service, ready.role, ready.performer) == ("input", "source", 5)
    assert ready.endpoints["pub"] == daemon.endpoints["pub"]
    sub = Subscriber(ctx, ready.endpoints["pub"])
    sub.collect(
        lambda s: s.count(p.Kind.ONSET) >= onsets.size and s.count(p.Kind.CONTROL) >= controls.size
    )
    thread.join(10)
    assert not thread.is_alive()
    got = sub.rows(p.Kind.ONSET)
    assert got["note"].tolist() == onsets["note"].tolist()
    assert got["velocity"].tolist() == onsets["velocity"].tolist()
    np.testing.assert_allclose(got["time_s"], 1000.0 + onsets["time_s"])
    assert (got["source"] == 5).all()
    assert sub.rows(p.Kind.CONTROL)["value"].tolist() == controls["value"].tolist()
    assert all(m.performer == 5 and m.flags == p.Flag.SIMULATED for m in sub.messages)
    assert_contiguous(sub)
    journal = load_journal(Path(daemon.endpoints["journal"]))
    assert journal.clean
    assert journal.onsets.tobytes() == got.tobytes()
    assert journal.controls.tobytes() == sub.rows(p.Kind.CONTROL).tobytes()
    assert journal.end is not None and journal.end["onsets"] == onsets.size
    assert journal.end["unknown_notes"] == {"99": 1}


def test_control_socket_ignores_garbage_and_keeps_answering(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    clock = MonotonicClock()
    src = FileSource(short_groove(tmp_path / "g.mid", notes=5), clock, ROLAND)
    daemon, thread, stop = start_daemon(src, clock, ctx, tmp_path, wait_subscribers=99)
    try:
        dealer = ctx.socket(zmq.DEALER)
        dealer.setsockopt(zmq.LINGER, 0)
        dealer.connect(daemon.endpoints["control"])
        for frames in (
            [b"", b"junk"],
            [b"", b"LDRM" + bytes(28)],
            [b"", *p.encode(p.Message(p.Kind.HEARTBEAT))],
        ):
            dealer.send_multipart(frames)
        ready = request_ready(ctx, daemon.endpoints["control"], p.Hello("test", "sink"), 5.0)
        assert ready.service == "input"
        assert not dealer.poll(100)  # nothing answered the garbage
        dealer.close(0)
        assert daemon.problems.counts["bad control message"] == 2
        assert daemon.problems.counts["unexpected control message"] == 1
    finally:
        stop.set()
        thread.join(5)


# ---------------------------------------------------------------- serial through a real pty


def pty_pair() -> tuple[int, str]:
    master, slave = os.openpty()
    name = os.ttyname(slave)
    os.close(slave)
    return master, name


def test_serial_source_reads_running_status_realtime_and_garbage_from_a_pty() -> None:
    master, name = pty_pair()
    try:
        clock = MonotonicClock()
        src = SerialSource(name, clock, MessageDecoder(ROLAND, 2), baud=115_200)
        src.open()
        before = clock.now()
        stream = b"".join(
            [
                bytes([0x12, 0x34]),  # garbage before any status
                bytes([0xB9, 4, 100]),  # hi-hat pedal
                bytes([0x99, 42, 80, 38, 0xF8, 90, 36, 70]),  # running status, a clock byte inside
                bytes([0xF0, 1, 2, 3, 0xF7]),  # sysex
                bytes([0xA9, 49, 127]),  # choke
            ]
        )
        os.write(master, stream)
        got: list[Any] = []
        deadline = time.monotonic() + 5
        while len(got) < 5 and time.monotonic() < deadline:
            got.extend(src.read(0.1))
        after = clock.now()
        kinds = [(type(e).__name__, getattr(e, "note", getattr(e, "number", None))) for e in got]
        assert kinds == [
            ("Control", 4),
            ("Onset", 42),
            ("Onset", 38),
            ("Onset", 36),
            ("Control", 49),
        ]
        assert [e.velocity for e in got if isinstance(e, Onset)] == [80, 90, 70]
        assert all(before <= e.time_s <= after for e in got)
        assert all(e.source == 2 for e in got)
        assert src.parser.stats.garbage_bytes == 2
        assert src.problems.counts["serial garbage"] == 2  # bytes
        src.close()
    finally:
        os.close(master)


def test_serial_daemon_survives_unplug_and_replug(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    link = tmp_path / "ttyDRUM"
    master, name = pty_pair()
    link.symlink_to(name)
    clock = MonotonicClock()
    src = SerialSource(str(link), clock, MessageDecoder(ROLAND, 1))
    daemon, thread, stop = start_daemon(
        src, clock, ctx, tmp_path, performer=1, wait_subscribers=1, reconnect_s=0.05
    )
    try:
        sub = Subscriber(ctx, daemon.endpoints["pub"])
        sub.collect(lambda s: src.is_open, 10)
        os.write(master, bytes([0x99, 38, 100, 36, 90]))
        sub.collect(lambda s: s.count(p.Kind.ONSET) >= 2)
        os.close(master)  # unplug
        link.unlink()
        sub.collect(lambda s: not src.is_open, 10)
        assert not src.is_open
        master, name = pty_pair()  # replug, maybe under another /dev/pts number
        link.symlink_to(name)
        t_plug = time.monotonic()
        sub.collect(lambda s: any(m.kind is p.Kind.GAP for m in s.messages), 10)
        reconnect_s = time.monotonic() - t_plug
        os.write(master, bytes([0x99, 42, 64]))
        sub.collect(lambda s: s.count(p.Kind.ONSET) >= 3)
        assert sub.rows(p.Kind.ONSET)["note"].tolist() == [38, 36, 42]
        gap = next(m.body for m in sub.messages if m.kind is p.Kind.GAP)
        assert isinstance(gap, p.Gap) and gap.reason is p.GapReason.SOURCE_LOST
        assert reconnect_s < 5.0  # generous bound on a loaded CI machine; typical ~0.1 s
        assert_contiguous(sub)
        assert daemon.problems.counts["source lost"] == 1
    finally:
        stop.set()
        thread.join(5)
        os.close(master)
    journal = load_journal(tmp_path / "sessions" / Path(daemon.endpoints["journal"]).name)
    assert journal.onsets["note"].tolist() == [38, 36, 42]
    assert [g.reason for g in journal.gaps] == [p.GapReason.SOURCE_LOST]


# ---------------------------------------------------------------- remote relay


def test_remote_source_relays_another_daemon_and_flags_it(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    path = short_groove(tmp_path / "g.mid", notes=40)
    onsets, controls = expected_events(path)
    clock = MonotonicClock()
    remote_src = RemoteSource(LOCAL.replace("*", "1"), clock, ctx)  # endpoint set below
    site_a, thread_a, stop_a = start_daemon(
        FileSource(path, clock, ROLAND, performer=7),
        clock,
        ctx,
        tmp_path / "a",
        performer=7,
        wait_subscribers=1,
    )
    remote_src.endpoint = site_a.endpoints["pub"]
    # Site B opens its remote source only once the test subscribes, so nothing is relayed
    # before anyone listens (PUB/SUB drops messages sent before a subscription arrives).
    site_b, thread_b, stop_b = start_daemon(
        remote_src, clock, ctx, tmp_path / "b", performer=8, wait_subscribers=1
    )
    try:
        sub = Subscriber(ctx, site_b.endpoints["pub"])
        sub.collect(
            lambda s: (
                s.count(p.Kind.ONSET) >= onsets.size and s.count(p.Kind.CONTROL) >= controls.size
            )
        )
        got = sub.rows(p.Kind.ONSET)
        assert got["note"].tolist() == onsets["note"].tolist()
        assert (got["source"] == 7).all()  # who played it survives the relay
        assert all(
            m.performer == 8 and m.flags & p.Flag.RELAYED
            for m in sub.messages
            if m.kind is p.Kind.ONSET
        )
        assert sub.rows(p.Kind.CONTROL)["value"].tolist() == controls["value"].tolist()
        assert_contiguous(sub)
    finally:
        stop_a.set()
        stop_b.set()
        thread_a.join(5)
        thread_b.join(5)


def test_remote_source_drops_bad_messages_and_reports_upstream_gaps(
    ctx: zmq.Context[zmq.Socket[bytes]],
) -> None:
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    clock = SteppedClock(3.0)
    src = RemoteSource(f"tcp://127.0.0.1:{port}", clock, ctx)
    src.open()
    try:
        rows = np.zeros(1, p.SPECS[p.Kind.ONSET].rows)
        rows["note"], rows["velocity"], rows["openness"] = 38, 99, np.nan
        # Subscriptions propagate asynchronously: send heartbeats until one arrives.
        got: list[Any] = []
        seq = 0
        while not src.tracker.stats:
            pub.send_multipart(p.encode(p.Message(p.Kind.HEARTBEAT, seq=seq)))
            seq += 1
            got.extend(src.read(0.05))
        for _ in range(3):  # drain the heartbeats still in flight; all after the first arrive
            got.extend(src.read(0.1))
        pub.send_multipart([b"garbage"])  # no subscribed topic: ZeroMQ filters it out
        pub.send_multipart([p.topic(p.Kind.ONSET) + b"garbage"])  # reaches decode: refused
        pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, rows, seq=seq)))
        pub.send_multipart(p.encode(p.Message(p.Kind.ONSET, rows, seq=seq + 3)))
        deadline = time.monotonic() + 5
        while sum(isinstance(e, Onset) for e in got) < 2 and time.monotonic() < deadline:
            got.extend(src.read(0.1))
        assert [type(e).__name__ for e in got] == ["Onset", "Gap", "Onset"]
        gap = got[1]
        assert isinstance(gap, p.Gap) and (gap.dropped, gap.reason) == (2, p.GapReason.UPSTREAM)
        assert got[0].time_s == got[2].time_s == 3.0  # restamped on the local clock
        assert src.problems.counts["bad remote message"] == 1
    finally:
        src.close()
        pub.close(0)


# ---------------------------------------------------------------- the real command, end to end


def test_cli_file_player_end_to_end(tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]) -> None:
    path = short_groove(tmp_path / "g.mid", notes=150, step_ticks=16)  # ~1.3 s of 60 notes/s
    onsets, controls = expected_events(path)
    home = tmp_path / "home"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--file",
            str(path),
            "--map",
            "roland-td",
            "--pub",
            LOCAL,
            "--control",
            LOCAL,
            "--performer",
            "4",
            "--wait-subscribers",
            "1",
            "--exit-at-end",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
        env={**os.environ, "LIVEDRUMMER_HOME": str(home)},
    )
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        ready = request_ready(ctx, info["control"], p.Hello("test", "sink"), 10.0)
        assert ready.endpoints["pub"] == info["pub"] and ready.performer == 4
        sub = Subscriber(ctx, info["pub"])
        sub.collect(
            lambda s: (
                s.count(p.Kind.ONSET) >= onsets.size and s.count(p.Kind.CONTROL) >= controls.size
            )
        )
        assert proc.wait(20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    got = sub.rows(p.Kind.ONSET)
    assert got["note"].tolist() == onsets["note"].tolist()
    assert got["velocity"].tolist() == onsets["velocity"].tolist()
    played = got["time_s"] - got["time_s"][0]
    np.testing.assert_allclose(np.diff(played), np.diff(onsets["time_s"]), atol=0.05)  # real time
    assert_contiguous(sub)
    sessions = list((home / "sessions").glob("*.ldj"))
    assert len(sessions) == 1 and Path(info["journal"]) == sessions[0]
    journal = load_journal(sessions[0])
    assert journal.clean
    assert journal.onsets.tobytes() == got.tobytes()
    # The session lists and exports through the CLI.
    env = {**os.environ, "LIVEDRUMMER_HOME": str(home)}
    listed = subprocess.run(
        [sys.executable, "-m", "services", "sessions", "list"],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
        check=True,
    ).stdout
    session_id = sessions[0].stem
    assert session_id in listed and f"{onsets.size} onsets" in listed and "(closed)" in listed
    out = tmp_path / "out.mid"
    subprocess.run(
        [sys.executable, "-m", "services", "sessions", "export", session_id, "-o", str(out)],
        env=env,
        cwd=REPO,
        check=True,
        capture_output=True,
    )
    back = read_midi_file(out, ROLAND)
    assert back.onsets["note"].tolist() == onsets["note"].tolist()


def test_cli_input_errors_are_one_line(tmp_path: Path) -> None:
    groove = str(short_groove(tmp_path / "g.mid", 5))
    cases = [
        (["--file", groove, "--pub", "bogus"], "pub endpoint"),
        (["--file", groove, "--pub", LOCAL, "--control", "tcp://127.0.0.1"], "control endpoint"),
        (["--file", str(tmp_path / "nope.mid")], "nope.mid: cannot read"),
        (["--file", "nope.mid", "--performer", "70000"], "--performer"),
        (["--serial", "/dev/null", "--baud", "1234"], "--baud"),
    ]
    for args, needle in cases:
        proc = subprocess.run(
            [sys.executable, "-m", "services", "input", *args, "--no-journal"],
            capture_output=True,
            text=True,
            cwd=REPO,
            timeout=60,
        )
        assert proc.returncode == 2, proc.stderr
        lines = proc.stderr.strip().splitlines()
        assert lines[-1].startswith("livedrummer: error: ") and needle in lines[-1], proc.stderr
        assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_cli_serial_daemon_journal_survives_stop_and_kill(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]], sig: str
) -> None:
    import signal

    master, name = pty_pair()
    home = tmp_path / "home"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--serial",
            name,
            "--map",
            "roland-td",
            "--pub",
            LOCAL,
            "--control",
            LOCAL,
            "--wait-subscribers",
            "1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
        env={**os.environ, "LIVEDRUMMER_HOME": str(home)},
    )
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        sub = Subscriber(ctx, info["pub"])
        deadline = time.monotonic() + 20
        while sub.count(p.Kind.ONSET) == 0 and time.monotonic() < deadline:
            # Probe until the daemon has opened the pty (bytes written before are lost, as
            # with a real device) and the subscription is live.
            os.write(master, bytes([0x99, 36, 1]))
            sub.collect(lambda s: s.count(p.Kind.ONSET) > 0, 0.1)
        sub.collect(lambda s: False, 0.3)  # probes still in flight
        base = sub.count(p.Kind.ONSET)
        notes = [(38, 42, 46)[i % 3] for i in range(200)]
        for i, note in enumerate(notes):
            os.write(master, bytes([0x99, note, 1 + i % 127]))
        sub.collect(lambda s: s.count(p.Kind.ONSET) >= base + len(notes))
        os.kill(proc.pid, getattr(signal, sig))
        code = proc.wait(20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    assert code == (0 if sig == "SIGTERM" else -9)
    got = sub.rows(p.Kind.ONSET)
    assert got["note"][base:].tolist() == notes
    journal = load_journal(Path(info["journal"]))
    assert journal.onsets.size == got.size, (
        journal.onsets.size,
        got.size,
        journal.records,
        journal.stop_reason,
        journal.discarded_bytes,
    )
    assert journal.onsets.tobytes() == got.tobytes()  # all that reached the bus is journaled
    assert journal.clean == (sig == "SIGTERM")


def test_file_source_loops_with_a_gap(tmp_path: Path) -> None:
    path = short_groove(tmp_path / "g.mid", notes=10)
    onsets, _ = expected_events(path)
    clock = SteppedClock(0.0)
    src = FileSource(path, clock, ROLAND, loop=True, loop_gap_s=2.0)
    src.open()
    got: list[Onset] = []
    while len(got) < 2 * onsets.size:
        got.extend(e for e in src.read(0.5) if isinstance(e, Onset))
    assert not src.finished()
    first, second = got[: onsets.size], got[onsets.size :]
    assert [o.note for o in second] == [o.note for o in first]
    length = max(read_midi_file(path, ROLAND).duration_s, float(onsets["time_s"][-1]))
    assert second[0].time_s - first[0].time_s == pytest.approx(length + 2.0)


def test_serial_flood_of_10000_notes_arrives_complete_and_in_order(
    tmp_path: Path, ctx: zmq.Context[zmq.Socket[bytes]]
) -> None:
    master, name = pty_pair()
    clock = MonotonicClock()
    src = SerialSource(name, clock, MessageDecoder(ROLAND, 0))
    daemon, thread, stop = start_daemon(src, clock, ctx, tmp_path, wait_subscribers=1)
    notes = [(36, 38, 42, 46, 49)[i % 5] for i in range(10_000)]
    # Running status, as a trigger board sends a roll: one status byte, then note/velocity pairs.
    stream = bytes([0x99]) + b"".join(bytes([n, 1 + i % 127]) for i, n in enumerate(notes))
    try:
        sub = Subscriber(ctx, daemon.endpoints["pub"])
        sub.sock.setsockopt(zmq.RCVHWM, 0)
        sub.collect(lambda s: src.is_open, 10)
        writer = threading.Thread(
            target=lambda: [
                os.write(master, stream[k : k + 512]) for k in range(0, len(stream), 512)
            ]
        )
        writer.start()
        sub.collect(lambda s: s.count(p.Kind.ONSET) >= len(notes), 60)
        writer.join()
    finally:
        stop.set()
        thread.join(10)
        os.close(master)
    got = sub.rows(p.Kind.ONSET)
    assert got["note"].tolist() == notes
    assert (np.diff(got["time_s"]) > 0).all()  # one stamp per message, in order
    assert_contiguous(sub)
    journal = load_journal(Path(daemon.endpoints["journal"]))
    assert journal.onsets.tobytes() == got.tobytes()
    assert src.parser.stats.running_status_used == len(notes) - 1


def test_cli_unwritable_journal_is_a_one_line_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--file",
            str(short_groove(tmp_path / "g.mid", 5)),
            "--map",
            "roland-td",
            "--pub",
            LOCAL,
            "--control",
            LOCAL,
            "--sessions-dir",
            str(blocker / "sessions"),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines()[-1].startswith("livedrummer: error: ")
    assert "cannot create journal" in proc.stderr and "Traceback" not in proc.stderr
