"""Rendered drums played into ``livedrummer input --audio`` through a real JACK server.

The daemon (``input --audio system``, a subprocess) and a player (:mod:`._audioplayer`,
another) are both PortAudio clients of the caller's JACK server; the daemon's inputs are
unplugged from the dummy backend's capture ports and fed from the player's outputs with
``jack_connect``. The caller subscribes to the daemon's bus and gets every onset with the
monotonic time it arrived; the player's block stamps place each true attack on that clock, so
attack → onset-on-the-bus latency is measured end to end (PortAudio and JACK in, recogniser,
ZeroMQ out). Runs under ``JACK_DEFAULT_SERVER`` (e.g. :func:`._jack.dummy_jack`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._paths import WORKDIR


@dataclass(frozen=True)
class LiveRun:
    onsets: np.ndarray  # ONSET_DTYPE rows as published
    arrival_s: np.ndarray  # monotonic time each arrived on the bus
    block_starts: np.ndarray  # player's blocks: first sample
    block_times: np.ndarray  # and monotonic time of their callback
    stderr: str
    sent_s: np.ndarray  # monotonic time the daemon sent each onset (the message's header)
    #: per onset (``trace=True``): the daemon's callback, hand-off and detector times
    #: (``input --trace``), else empty
    trace: np.ndarray
    #: the daemon's scheduling policy while it listened (``os.SCHED_FIFO`` when ``realtime``
    #: was asked for and granted)
    daemon_policy: int = os.SCHED_OTHER

    def attack_times(self, times_s: np.ndarray, sr: int = 48_000) -> np.ndarray:
        """Monotonic time of each sample time ``times_s`` of the played audio."""
        idx = np.round(np.asarray(times_s) * sr).astype(np.int64)
        k = np.searchsorted(self.block_starts, idx, side="right") - 1
        k = np.clip(k, 0, len(self.block_starts) - 1)
        return np.asarray(self.block_times[k] + (idx - self.block_starts[k]) / sr)

    def block_time(self, samples: np.ndarray) -> np.ndarray:
        """Monotonic time of the player's callback for the block holding each sample index."""
        k = np.searchsorted(self.block_starts, np.asarray(samples), side="right") - 1
        return np.asarray(self.block_times[np.clip(k, 0, len(self.block_starts) - 1)])

    def file_times(self, stamps_s: np.ndarray, sr: int = 48_000) -> np.ndarray:
        """The inverse: the time in the played audio of each monotonic time ``stamps_s``."""
        k = np.searchsorted(self.block_times, np.asarray(stamps_s), side="right") - 1
        k = np.clip(k, 0, len(self.block_times) - 1)
        samples = self.block_starts[k] + (np.asarray(stamps_s) - self.block_times[k]) * sr
        return np.asarray(samples / sr)


def _ports() -> list[str]:
    return subprocess.run(["jack_lsp"], capture_output=True, text=True, timeout=10).stdout.split(
        "\n"
    )


def play_into_daemon(
    audio: np.ndarray, extra: list[str] | None = None, trace: bool = False, realtime: int = 0
) -> LiveRun:
    """Play ``audio`` into a fresh ``input --audio`` (``extra``: more of its options) and
    collect what it publishes. ``realtime``: a ``SCHED_FIFO`` priority for the daemon
    (``input --realtime``) and for this side's subscriber (the thread that polls and stamps
    arrivals, and ZeroMQ's I/O thread), as a stage rig would run both; 0: the normal policy.
    The player keeps the normal policy either way (its callbacks are JACK's)."""
    import zmq

    from livedrummer import protocol as p

    channels = 1 if audio.ndim == 1 else audio.shape[1]
    before = set(_ports())
    any_port = "tcp://127.0.0.1:*"
    cmd = [
        sys.executable,
        "-m",
        "services",
        "input",
        "--audio",
        "system",
        "--no-journal",
        "--pub",
        any_port,
        "--control",
        any_port,
        *(extra or []),
    ]
    if realtime:
        cmd += ["--realtime", str(realtime)]
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    if realtime:  # ZeroMQ's I/O thread starts with the first socket, at this priority
        ctx.set(zmq.THREAD_SCHED_POLICY, os.SCHED_FIFO)
        ctx.set(zmq.THREAD_PRIORITY, realtime)
    sub = ctx.socket(zmq.SUB)
    player = None
    err = ""
    with tempfile.TemporaryDirectory() as tmp:
        trace_file = Path(tmp) / "trace.json"
        if trace:
            cmd += ["--trace", str(trace_file)]
        daemon = subprocess.Popen(
            cmd, cwd=WORKDIR, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        try:
            assert daemon.stdout is not None
            line = daemon.stdout.readline()
            if not line:
                raise RuntimeError(f"input --audio did not start: {daemon.communicate()[1]}")
            endpoints = json.loads(line)
            sub.setsockopt(zmq.LINGER, 0)
            sub.setsockopt(zmq.SUBSCRIBE, p.topic(p.Kind.ONSET))
            sub.connect(endpoints["pub"])
            mine = _wait_ports(before, "in_", channels)
            player, stamps = _start_player(audio, mine, Path(tmp))
            time.sleep(0.3)  # the subscription settles (nothing is played yet)
            policy = os.sched_getscheduler(daemon.pid)
            if realtime:  # this thread only: the daemon and the player are already started
                from ..process.realtime import request_realtime

                request_realtime(realtime, "bench subscriber")
            assert player.stdin is not None
            player.stdin.write("go\n")
            player.stdin.flush()
            rows: list[np.ndarray] = []
            arrivals: list[float] = []
            sent: list[float] = []
            deadline = time.monotonic() + len(audio) / 48_000 + 20
            blocks: list[list[float]] | None = None
            while time.monotonic() < deadline:
                if sub.poll(10):
                    msg = p.decode(sub.recv_multipart())
                    now = time.monotonic()
                    rows.append(msg.rows)
                    arrivals += [now] * len(msg.rows)
                    sent += [msg.send_time_s] * len(msg.rows)
                if blocks is None and player.poll() is not None:
                    blocks = json.loads(stamps.read_text())["blocks"]
                    deadline = min(deadline, time.monotonic() + 0.5)
            if blocks is None:
                raise RuntimeError("the player did not finish")
        finally:
            if realtime:
                os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
            if player is not None and player.poll() is None:
                player.kill()
            daemon.terminate()
            try:
                err = daemon.communicate(timeout=10)[1]
            except subprocess.TimeoutExpired:
                daemon.kill()
                err = daemon.communicate()[1]
            sub.close(0)
            ctx.term()
        traced = json.loads(trace_file.read_text())["hits"] if trace_file.exists() else []
    from livedrummer.timeline.events import ONSET_DTYPE

    onsets = np.concatenate(rows) if rows else np.zeros(0, ONSET_DTYPE)
    b = np.array(blocks, float).reshape(-1, 2)
    return LiveRun(
        onsets,
        np.array(arrivals),
        b[:, 0].astype(np.int64),
        b[:, 1],
        err,
        np.array(sent),
        np.array(traced, float).reshape(-1, 3),
        policy,
    )


def _start_player(audio: np.ndarray, inputs: list[str], tmp: Path) -> tuple[Any, Path]:
    """The player process, its outputs connected to ``inputs`` (and only to them), waiting
    for "go" on its stdin; and the file its block stamps will be written to."""
    channels = 1 if audio.ndim == 1 else audio.shape[1]
    path = tmp / "audio.npy"
    np.save(path, audio.astype(np.float32))
    stamps = tmp / "stamps.json"
    before = set(_ports())
    player = subprocess.Popen(
        [sys.executable, "-m", "services.bench._audioplayer", str(path), str(stamps)],
        cwd=WORKDIR,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert player.stdout is not None
    json.loads(player.stdout.readline())
    theirs = _wait_ports(before, "out_", channels)
    for inp, out in zip(inputs, theirs, strict=True):
        for port in _connections(inp):
            subprocess.run(["jack_disconnect", port, inp], timeout=10, check=False)
        subprocess.run(["jack_connect", out, inp], timeout=10, check=True)
    return player, stamps


def learn_from(audio: np.ndarray, args: list[str]) -> subprocess.CompletedProcess[str]:
    """``livedrummer audio learn --audio system ARGS`` hearing ``audio`` played through JACK."""
    channels = 1 if audio.ndim == 1 else audio.shape[1]
    before = set(_ports())
    cmd = [sys.executable, "-m", "services", "audio", "learn", "--audio", "system", *args]
    learn = subprocess.Popen(
        cmd, cwd=WORKDIR, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    player = None
    with tempfile.TemporaryDirectory() as tmp:
        try:
            assert learn.stdout is not None
            first = learn.stdout.readline()  # "hit the ...": the stream is open
            if not first:
                out, err = learn.communicate()
                return subprocess.CompletedProcess(cmd, learn.returncode, out, err)
            mine = _wait_ports(before, "in_", channels)
            player, _stamps = _start_player(audio, mine, Path(tmp))
            assert player.stdin is not None
            player.stdin.write("go\n")
            player.stdin.flush()
            out, err = learn.communicate(timeout=len(audio) / 48_000 + 60)
            return subprocess.CompletedProcess(cmd, learn.returncode, first + out, err)
        finally:
            if player is not None:
                try:  # let it finish its audio: a JACK client killed mid-cycle stalls jackd
                    player.wait(timeout=len(audio) / 48_000 + 5)
                except subprocess.TimeoutExpired:
                    player.kill()
                    player.wait()
            if learn.poll() is None:
                learn.kill()
                learn.wait()


def _wait_ports(before: set[str], kind: str, n: int, timeout_s: float = 10.0) -> list[str]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        new = sorted(p for p in set(_ports()) - before if kind in p.rsplit(":", 1)[-1])
        if len(new) >= n:
            return new[:n]
        time.sleep(0.05)
    raise RuntimeError(f"no new JACK {kind} ports appeared")


def _connections(port: str) -> list[str]:
    out = subprocess.run(["jack_lsp", "-c", port], capture_output=True, text=True, timeout=10)
    return [line.strip() for line in out.stdout.splitlines()[1:] if line.startswith(" ")]
