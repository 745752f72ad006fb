"""A JACK audio player for the live recogniser's test and benchmark (run as its own process).

``python -m services.bench._audioplayer AUDIO.npy STAMPS.json``: opens a PortAudio output
stream on the JACK device ``system`` (float32, 48 kHz, 128-sample blocks, the file's
channels) playing silence, prints ``{"ready": true}``, waits for a line on stdin, then plays
the file once and writes ``{"blocks": [[first_sample, monotonic_s], ...]}`` to STAMPS.json:
for every block it handed to JACK, the file sample it started with and ``CLOCK_MONOTONIC``
when the callback ran, the moment that block went out (the JACK cycle it belongs to), from
which the caller places each attack on the clock the input daemon stamps with.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any

import numpy as np


def main(argv: list[str]) -> int:
    import sounddevice as sd

    audio = np.load(argv[0]).astype(np.float32)
    if audio.ndim == 1:
        audio = audio[:, None]
    state = {"pos": -1}
    stamps: list[tuple[int, float]] = []
    done = threading.Event()

    def callback(out: np.ndarray, frames: int, _time: Any, _status: Any) -> None:
        now = time.monotonic()
        pos = state["pos"]
        out.fill(0.0)
        if pos < 0:
            return
        part = audio[pos : pos + frames]
        out[: len(part)] = part
        stamps.append((pos, now))
        state["pos"] = pos + frames
        if pos + frames >= len(audio):
            state["pos"] = -1
            done.set()

    with sd.OutputStream(
        device="system",
        channels=audio.shape[1],
        samplerate=48_000,
        blocksize=128,
        dtype="float32",
        callback=callback,
    ):
        print(json.dumps({"ready": True}), flush=True)
        sys.stdin.readline()
        state["pos"] = 0
        done.wait(len(audio) / 48_000 + 30)
        time.sleep(0.1)
    with open(argv[1], "w") as f:
        json.dump({"blocks": stamps}, f)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
