"""A private JACK server on the dummy backend, for benchmarks and tests (no sound card).

``jackd --no-realtime -S -n NAME -d dummy``: a unique server name so runs never meet, the
synchronous mode (-S: the asynchronous one lost or repeated MIDI on a busy 2-core machine
without real-time priority), started and waited for with ``jack_wait``. Clients reach it
through ``JACK_DEFAULT_SERVER=NAME`` (and ``JACK_NO_AUDIO_RESERVATION=1``), which the caller
sets where its clients live: :func:`jack_env` gives both.
"""

from __future__ import annotations

import shutil
import subprocess
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from typing import IO


class JackError(RuntimeError):
    """jackd is not installed or did not start; the message says which."""


def jack_env(name: str) -> dict[str, str]:
    return {"JACK_DEFAULT_SERVER": name, "JACK_NO_AUDIO_RESERVATION": "1"}


@contextmanager
def dummy_jack(
    prefix: str,
    period: int = 128,
    log: IO[str] | None = None,
    sync: bool = True,
    realtime: bool = False,
    rate: int = 48_000,
    priority: int | None = None,
) -> Iterator[str]:
    """Run a server named ``PREFIX-xxxxxxxx`` while the block runs; yields its name.

    ``sync=False`` runs JACK's default asynchronous mode, ``realtime=True`` asks for realtime
    scheduling (``-R``; it falls back to normal scheduling where that is not permitted); ``rate``
    is the sample rate in Hz, ``priority`` the real-time priority (``-P``; jackd's default
    where None).
    """
    if shutil.which("jackd") is None or shutil.which("jack_wait") is None:
        raise JackError("jackd not installed (Debian: apt-get install jackd2)")
    import os

    name = f"{prefix}-{uuid.uuid4().hex[:8]}"
    env = {**os.environ, **jack_env(name)}
    out = log if log is not None else subprocess.DEVNULL
    proc = subprocess.Popen(
        [
            "jackd",
            "-R" if realtime else "--no-realtime",
            *(["-S"] if sync else []),
            *(["-P", str(priority)] if realtime and priority is not None else []),
            "-n",
            name,
            "-d",
            "dummy",
            "-r",
            str(rate),
            "-p",
            str(period),
        ],
        stdout=out,
        stderr=subprocess.STDOUT,
        env=env,
    )
    try:
        waited = subprocess.run(
            ["jack_wait", "-s", name, "-w", "-t", "10"], capture_output=True, env=env
        )
        if waited.returncode != 0 or proc.poll() is not None:
            raise JackError(f"jackd -d dummy ({name}) did not start")
        yield name
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
