"""Shared fixtures: the Groove MIDI Dataset beside the checkout, and small MIDI file builders."""

from __future__ import annotations

import os
import shutil
import subprocess
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import mido
import pytest

REPO = Path(__file__).resolve().parent.parent
GROOVE = REPO.parent / "shared" / "data" / "groove"


@pytest.fixture(scope="session")
def groove_dir() -> Path:
    if not GROOVE.is_dir():  # CI always has ../shared beside the clone
        _unavailable(f"Groove MIDI Dataset not found at {GROOVE}")
    return GROOVE


@pytest.fixture(scope="session")
def groove_files(groove_dir: Path) -> list[Path]:
    return sorted(groove_dir.rglob("*.mid"))


MidiWriter = Callable[..., Path]


@pytest.fixture
def write_midi(tmp_path: Path) -> MidiWriter:
    """Write a one-track (or multi-track) MIDI file from (delta_ticks, mido message) lists."""

    def write(*tracks: list[mido.Message], tpb: int = 480, name: str = "t.mid") -> Path:
        mid = mido.MidiFile(ticks_per_beat=tpb)
        for messages in tracks:
            track = mido.MidiTrack()
            track.extend(messages)
            mid.tracks.append(track)
        path = tmp_path / name
        mid.save(path)
        return path

    return write


def _unavailable(reason: str) -> None:
    """Skip on a developer's machine; fail under CI, whose set-up installs every real part."""
    if os.environ.get("CI"):
        pytest.fail(reason)
    pytest.skip(reason)


@pytest.fixture
def jack_server(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[str]:
    """A real JACK server on the dummy backend (no sound card), synchronous mode (-S).

    The asynchronous mode lost or repeated MIDI on a busy 2-core machine without realtime
    priority; -S delivered every note. The server gets a unique name, exported to the test
    through JACK_DEFAULT_SERVER.
    """
    if shutil.which("jackd") is None or shutil.which("jack_wait") is None:
        _unavailable("jackd not installed (Debian: apt-get install jackd2)")
    name = f"ldtest-{uuid.uuid4().hex[:8]}"
    env = {**os.environ, "JACK_NO_AUDIO_RESERVATION": "1", "JACK_DEFAULT_SERVER": name}
    log_path = tmp_path / "jackd.log"
    with log_path.open("w") as log:
        proc = subprocess.Popen(
            ["jackd", "--no-realtime", "-S", "-n", name, "-d", "dummy", "-r", "48000", "-p", "128"],
            stdout=log, stderr=subprocess.STDOUT, env=env,
        )  # fmt: skip
        try:
            waited = subprocess.run(
                ["jack_wait", "-s", name, "-w", "-t", "10"], capture_output=True, env=env
            )
            if waited.returncode != 0 or proc.poll() is not None:
                _unavailable(f"jackd -d dummy did not start: {log_path.read_text()[-300:]}")
            monkeypatch.setenv("JACK_DEFAULT_SERVER", name)
            monkeypatch.setenv("JACK_NO_AUDIO_RESERVATION", "1")
            yield name
        finally:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
