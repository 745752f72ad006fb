"""Shared fixtures: the Groove MIDI Dataset beside the checkout, and small MIDI file builders.

Every test is also marked ``e2e`` (real processes, sockets, JACK, windows) or ``gpu`` (an
OpenGL context) from what its code reaches (:mod:`markers`), so ``make test-fast`` can leave
them out; ``slow`` is written by hand on the pure tests that take long.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path

import mido
import pytest
from markers import marks_of

from livedrummer.body.rig import Rig, build_rig
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.performance import Performance
from services.bench._jack import JackError, dummy_jack, jack_env
from services.cli.files import DEMO_MAP, demo_groove

REPO = Path(__file__).resolve().parent.parent
GROOVE = REPO.parent / "shared" / "data" / "groove"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Add the ``e2e`` and ``gpu`` marks :func:`markers.marks_of` finds (see :mod:`markers`)."""
    for item in items:
        if not isinstance(item, pytest.Function):
            continue
        qualname = item.originalname
        if item.cls is not None:
            qualname = f"{item.cls.__name__}.{qualname}"
        for mark in sorted(marks_of(item.path, qualname, item.fixturenames)):
            item.add_marker(mark)


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


@pytest.fixture(scope="session")
def gl_ok() -> None:
    """A headless OpenGL context (EGL; Mesa llvmpipe without a GPU) can be made."""
    from services.display.context import DisplayError, headless_context

    try:
        headless_context().release()
    except DisplayError as exc:
        _unavailable(str(exc))


def _jack(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, sync: bool, realtime: bool
) -> Iterator[str]:
    log_path = tmp_path / "jackd.log"
    with log_path.open("w") as log:
        try:
            with dummy_jack("ldtest", log=log, sync=sync, realtime=realtime) as name:
                for key, value in jack_env(name).items():
                    monkeypatch.setenv(key, value)
                yield name
        except JackError as exc:
            _unavailable(f"{exc}: {log_path.read_text()[-300:]}")


@pytest.fixture
def jack_server(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[str]:
    """A real JACK server on the dummy backend (no sound card), synchronous mode (-S).

    The server gets a unique name, exported to the test through JACK_DEFAULT_SERVER.
    """
    yield from _jack(monkeypatch, tmp_path, sync=True, realtime=False)


@pytest.fixture
def jack_default_server(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[str]:
    """The same in JACK's default mode (asynchronous, realtime asked for), as a rig left at
    jackd's defaults runs it: the sound tests run there."""
    yield from _jack(monkeypatch, tmp_path, sync=False, realtime=True)


@pytest.fixture
def jack_rig_server(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[str]:
    """The same as JACK settings for a rig (docs/guide/rig.md) ask: realtime and synchronous (``-R
    -S``). The tests that count every note through JACK run here: in the asynchronous mode a
    cycle a client's JACK thread misses (a stalled virtual machine misses some even at
    realtime priority) loses that cycle's MIDI, by JACK's design (``livedrummer bench
    jack_modes`` measures it); with ``-S`` the server waits for the late client."""
    yield from _jack(monkeypatch, tmp_path, sync=True, realtime=True)


@pytest.fixture(scope="session")
def rig() -> Rig:
    """The default kit's rig (built once: the live synth tests share it)."""
    return build_rig(load_kit("rock5"))


@pytest.fixture(scope="session")
def groove() -> Performance:
    """The bundled demo groove, read once."""
    return read_midi_file(demo_groove(), load_note_map(DEMO_MAP))
