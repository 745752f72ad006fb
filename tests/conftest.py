"""Shared fixtures: the Groove MIDI Dataset beside the checkout, and small MIDI file builders."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import mido
import pytest

REPO = Path(__file__).resolve().parent.parent
GROOVE = REPO.parent / "shared" / "data" / "groove"


@pytest.fixture(scope="session")
def groove_dir() -> Path:
    if not GROOVE.is_dir():
        if os.environ.get("CI"):  # CI always has ../shared: a missing corpus is a failure there
            pytest.fail(f"Groove MIDI Dataset not found at {GROOVE}")
        pytest.skip(f"Groove MIDI Dataset not found at {GROOVE}")
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
