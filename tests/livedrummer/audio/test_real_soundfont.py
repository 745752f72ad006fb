"""A real sampled General MIDI SoundFont (Debian's timgm6mb-soundfont, which CI installs):
attacks on the onsets to within a video frame, and velocity heard as loudness."""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np
import pytest
from test_soundfont import onsets

from livedrummer.audio.soundfont import render_soundfont

SR = 48_000
FRAME_S = 1 / 30
TIMGM = Path("/usr/share/sounds/sf2/TimGM6mb.sf2")


@pytest.fixture(scope="module")
def timgm() -> Path:
    try:
        import fluidsynth  # noqa: F401
    except (ImportError, OSError) as exc:
        reason = f"FluidSynth not loadable ({exc}; Debian: apt-get install libfluidsynth3)"
    else:
        reason = "" if TIMGM.is_file() else f"{TIMGM} missing (Debian: timgm6mb-soundfont)"
    if reason:
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)
    return TIMGM


def envelope(audio: np.ndarray) -> np.ndarray:
    return np.abs(audio).max(axis=1)


def test_each_instrument_attacks_within_a_frame_of_its_onset(timgm: Path) -> None:
    notes = [36, 38, 42, 45, 37, 46, 51, 49]  # kick, snare, hats, tom, side stick, ride, crash
    times = [0.3 + 0.9 * k for k in range(len(notes))]
    audio = render_soundfont(
        onsets([(t, n, 110) for t, n in zip(times, notes, strict=True)]), times[-1] + 0.8, timgm, SR
    )
    env = envelope(audio)
    assert env[: int(0.29 * SR)].max() < 1e-4  # nothing before the first onset
    for t, note in zip(times, notes, strict=True):
        window = env[int((t - 0.25) * SR) : int((t + 0.25) * SR)]
        before = env[int((t - 0.25) * SR) : int(t * SR)]
        # the attack: the first sample well above what still rang before the onset
        level = max(0.3 * float(window.max()), 4 * float(before.max()) if before.size else 0)
        attack = (int((t - 0.25) * SR) + int(np.argmax(window > level))) / SR
        assert abs(attack - t) <= FRAME_S, (note, attack - t)


def test_a_harder_stroke_is_louder(timgm: Path) -> None:
    velocities = [30, 70, 110, 127]
    times = [0.2 + 0.7 * k for k in range(len(velocities))]
    hits = [(t, 38, v) for t, v in zip(times, velocities, strict=True)]
    env = envelope(render_soundfont(onsets(hits), times[-1] + 0.7, timgm, SR))
    peaks = [float(env[int(t * SR) : int((t + 0.2) * SR)].max()) for t in times]
    assert all(b > 1.15 * a for a, b in itertools.pairwise(peaks)), peaks
