"""``livedrummer bench practice_click``: the practice click's audio onsets against its beat grid.

Starts a private ``jackd -d dummy`` server, plays the practice click
(:class:`services.practice.click.ClickPlayer`, PortAudio on JACK) at a grid of shared-clock
times, and records the click's own output port through a JACK connection into a PortAudio
input stream of the same process. Each recorded block is placed on the shared clock by its ADC
time (the same mapping the player uses for DAC times); a click's onset is the first sample over
a threshold after silence. Prints, over ``--clicks`` clicks at ``--bpm``: the median error
(onset minus grid time), the p99 of |error| and the p99 of |error - median| (the jitter, which
no calibration can remove), and the number of clicks found.

Limits: the loopback inside the JACK graph is not a loudspeaker and microphone: the click is
placed at PortAudio's DAC time of the output and found at the ADC time of the input, and the
two are not the same point of the graph, so the median is a constant of this path (a few JACK
periods), not the click's error at a loudspeaker; the jitter is the figure that says whether
the click is placed by the audio clock, whatever Python did meanwhile (the dummy backend's
clock runs on the OS timer, so a busy machine adds a little of its own).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import threading
import time

import numpy as np

from ._jack import JackError, dummy_jack, jack_env

RATE = 48_000
THRESHOLD = 0.02


def measure(clicks: int, bpm: float, period: int) -> dict[str, float]:
    with dummy_jack("ldclick", period=period) as name:
        os.environ.update(jack_env(name))
        import sounddevice as sd  # after the server is up: PortAudio lists host APIs at import

        from ..practice.click import ClickPlayer

        blocks: list[tuple[float, np.ndarray]] = []
        lock = threading.Lock()
        player = ClickPlayer("beep", 0.8)
        offset = time.monotonic() - float(player.stream.time)

        def record(data: np.ndarray, frames: int, when: object, _status: object) -> None:
            adc = float(when.inputBufferAdcTime) + offset  # type: ignore[attr-defined]
            with lock:
                blocks.append((adc, data[:, 0].copy()))

        rec = sd.InputStream(samplerate=RATE, channels=1, dtype="float32", callback=record)
        rec.start()
        try:
            ports = subprocess.run(
                ["jack_lsp"], capture_output=True, text=True, env=os.environ, check=True
            ).stdout.split()
            outs = [p for p in ports if "PortAudio" in p and "out" in p]
            ins = [p for p in ports if "PortAudio" in p and "in" in p]
            if not outs or not ins:
                raise JackError(f"no PortAudio ports on {name}: {ports}")
            for p in ports:  # only the loopback: nothing from the dummy capture
                if p.startswith("system:capture"):
                    subprocess.run(
                        ["jack_disconnect", p, ins[0]], capture_output=True, env=os.environ
                    )
            subprocess.run(["jack_connect", outs[0], ins[0]], check=True, env=os.environ)
            start = time.monotonic() + 1.0
            grid = start + np.arange(clicks) * 60.0 / bpm
            player.schedule(grid, np.arange(clicks) % 4 == 0)
            while time.monotonic() < grid[-1] + 0.5:
                time.sleep(0.05)
        finally:
            rec.stop()
            rec.close()
            player.close()
            sd._terminate()  # before the server goes: PortAudio's JACK client must leave first
    with lock:
        t0 = np.concatenate([a + np.arange(b.size) / RATE for a, b in blocks])
        x = np.concatenate([b for _, b in blocks])
    loud = np.abs(x) > THRESHOLD
    onsets = []
    last = -1.0
    for i in np.flatnonzero(loud).tolist():
        if t0[i] - last > 0.1:
            onsets.append(t0[i])
        last = t0[i]
    found = np.array(onsets)
    errors = []
    for g in grid:
        if found.size:
            k = int(np.argmin(np.abs(found - g)))
            if abs(found[k] - g) < 0.1:
                errors.append((found[k] - g) * 1e3)
    err = np.array(errors)
    if not err.size:
        raise JackError("no click came back through the loopback")
    median = float(np.median(err))
    return {
        "clicks": float(clicks),
        "found": float(err.size),
        "median_ms": median,
        "p99_abs_ms": float(np.percentile(np.abs(err), 99)),
        "p99_jitter_ms": float(np.percentile(np.abs(err - median), 99)),
        "period": float(period),
    }


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench practice_click")
    parser.add_argument("--clicks", type=int, default=64, help="clicks to play (default 64)")
    parser.add_argument("--bpm", type=float, default=240.0, help="click tempo (default 240)")
    parser.add_argument("--period", type=int, default=256, help="JACK period (default 256)")
    args = parser.parse_args(argv)
    r = measure(args.clicks, args.bpm, args.period)
    print(
        f"practice click through JACK (dummy, period {args.period} at 48 kHz): "
        f"{int(r['found'])}/{int(r['clicks'])} clicks found; onset - grid: median "
        f"{r['median_ms']:+.2f} ms, p99 |error| {r['p99_abs_ms']:.2f} ms, p99 jitter "
        f"{r['p99_jitter_ms']:.2f} ms"
    )
    return 0
