"""Record what livedrummer sounds through a real JACK server, on the shared clock.

:class:`JackRecorder` runs ``services/bench/jack_rec.c`` (compiled for the run: cc and Debian's
libjack-jackd2-dev): one input port to which every audio output of every other client is
connected as it appears (JACK sums them), written per cycle with the shared-clock
(``CLOCK_MONOTONIC``) time the cycle ran (not JACK's frame time: on the dummy driver its
estimate drifts by tens of ms in the first seconds). :meth:`JackRecorder.stop` returns a
:class:`Recording`: the samples and, per sample, the time it is heard (its cycle's time plus
its place in the cycle and the playback latency the source port reports, the highest read
every 20 ms while connected: right after the connection JACK may not have computed it yet,
and a run read 0 then came out 5.3 ms early throughout). :func:`attacks` finds the sound's
attacks in it. Tests and ``bench audio`` use both.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._jack import JackError

HERE = Path(__file__).resolve().parent
RATE = 48_000


def build_recorder(folder: Path) -> Path:
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise JackError("no C compiler (Debian: apt-get install gcc)")
    exe = folder / "jack_rec"
    done = subprocess.run(
        [cc, "-O2", "-o", str(exe), str(HERE / "jack_rec.c"), "-ljack"],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1:]
        raise JackError(f"cannot build the recorder (Debian: libjack-jackd2-dev): {last}")
    return exe


@dataclass(frozen=True)
class Recording:
    samples: np.ndarray  # float32, mono (the sum of every source)
    times: np.ndarray  # float64 shared-clock seconds each sample is heard
    sources: list[str]
    cycles: np.ndarray  # float64 shared-clock seconds each JACK cycle ran
    xruns: int = 0  # JACK's xrun count while recording
    load_mean: float = 0.0  # JACK's DSP load (%), sampled every 20 ms
    load_max: float = 0.0


class JackRecorder:
    """Start recording at once (the server named by ``env``); :meth:`stop` ends it."""

    def __init__(self, env: dict[str, str]) -> None:
        self._dir = Path(tempfile.mkdtemp(prefix="ldrec-"))
        exe = build_recorder(self._dir)
        self._out = self._dir / "rec.bin"
        self.proc = subprocess.Popen(
            [str(exe), str(self._out)], stdout=subprocess.PIPE, text=True, env=env
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline().split()
        if not line or line[0] != "ready":
            self.proc.kill()
            raise JackError("the recorder did not start")
        self.offset_us = int(line[2]) - int(line[1])  # monotonic - JACK clock

    def stop(self) -> Recording:
        self.proc.terminate()
        out, _ = self.proc.communicate(timeout=10)
        sources, latency, stats = [], 0, (0, 0.0, 0.0)
        final: list[int] = []  # the latency read while connected (see jack_rec.c)
        for line in out.splitlines():
            word = line.split()
            if word and word[0] == "connected":
                sources.append(word[1])
                latency = max(latency, int(word[2]))
            elif word and word[0] == "latency":
                final.append(int(word[1]))
            elif word and word[0] == "stats":
                stats = (int(word[1]), float(word[2]), float(word[3]))
        latency = max(final, default=latency)
        raw = self._out.read_bytes()
        shutil.rmtree(self._dir, ignore_errors=True)
        chunks, times, cycles, at = [], [], [], 0
        while at + 12 <= len(raw):
            us = int(np.frombuffer(raw, np.int64, 1, at)[0])
            n = int(np.frombuffer(raw, np.uint32, 1, at + 8)[0])
            if at + 12 + 4 * n > len(raw):
                break
            chunks.append(np.frombuffer(raw, np.float32, n, at + 12))
            cycles.append(us * 1e-6)
            times.append(us * 1e-6 + (np.arange(n) + latency) / RATE)
            at += 12 + 4 * n
        if not chunks:
            return Recording(np.zeros(0, np.float32), np.zeros(0), sources, np.zeros(0), *stats)
        return Recording(
            np.concatenate(chunks), np.concatenate(times), sources, np.array(cycles), *stats
        )


def steady(
    rec: Recording,
    at: np.ndarray,
    before_s: float = 0.1,
    after_s: float = 0.05,
    slack_s: float = 0.001,
) -> np.ndarray:
    """Per time in ``at``: whether the JACK graph ran on time around it (every cycle from
    ``before_s`` before to ``after_s`` after began within ``slack_s`` of one period after
    the previous one). A stalled cycle (the dummy driver of a loaded machine) moves every
    sound around it, ours or not, so timing is judged only where the graph was steady."""
    period = len(rec.samples) / max(len(rec.cycles), 1) / RATE
    bad_t = rec.cycles[1:][np.abs(np.diff(rec.cycles) - period) > slack_s]
    ok = np.ones(len(at), bool)
    for i, t in enumerate(at.tolist()):
        ok[i] = not np.any((bad_t > t - before_s) & (bad_t < t + after_s))
    return ok


def attacks(
    rec: Recording, threshold: float = 0.02, rise: float = 3.0, gap_s: float = 0.08, block: int = 64
) -> np.ndarray:
    """Shared-clock times of the sound's attacks: the first sample above ``threshold`` of a
    ``block`` whose peak is ``rise`` times the peak of the 20 blocks before it (so a hit over
    a ringing one counts), at least ``gap_s`` after the previous attack."""
    n = len(rec.samples) // block
    env = np.abs(rec.samples[: n * block]).reshape(n, block).max(axis=1)
    found: list[float] = []
    for i in np.flatnonzero(env > threshold).tolist():
        before = float(env[max(i - 20, 0) : i].max()) if i else 0.0
        if env[i] < rise * before:
            continue
        k = i * block + int(np.argmax(np.abs(rec.samples[i * block : (i + 1) * block]) > threshold))
        if not found or rec.times[k] - found[-1] >= gap_s:
            found.append(float(rec.times[k]))
    return np.array(found)
