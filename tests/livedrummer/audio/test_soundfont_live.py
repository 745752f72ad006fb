"""The SoundFont played live (``SoundFontLiveMixer``) against its offline twin
(``render_soundfont``): the same strokes, rendered block by block with random block sizes."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from sf2_writer import write_sf2

from livedrummer.audio.soundfont import render_soundfont
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone
from livedrummer.timeline.events import ONSET_DTYPE

SR = 48_000
TIMGM = Path("/usr/share/sounds/sf2/TimGM6mb.sf2")


@pytest.fixture(scope="module", autouse=True)
def needs_fluidsynth() -> None:
    try:
        import fluidsynth  # noqa: F401
    except (ImportError, OSError) as exc:
        reason = f"FluidSynth not loadable ({exc}; Debian: apt-get install libfluidsynth3)"
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)


def strokes(seed: int, n: int = 40, seconds: float = 3.0) -> np.ndarray:
    """Random strokes on kick, snare, closed and open hi-hat, ride and crash; some of one note
    closer than the note-off hold, so a stroke's hold is cut by the next."""
    rng = np.random.default_rng(seed)
    kinds = [(36, "kick", Zone.HEAD, HiHat.NONE), (38, "snare", Zone.HEAD, HiHat.NONE),
             (42, "hihat", Zone.BOW, HiHat.CLOSED), (46, "hihat", Zone.BOW, HiHat.OPEN),
             (51, "ride", Zone.BOW, HiHat.NONE), (49, "crash1", Zone.BOW, HiHat.NONE)]  # fmt: skip
    out = np.zeros(n, ONSET_DTYPE)
    out["time_s"] = np.sort(rng.uniform(0.0, seconds - 1.0, n))
    out["channel"] = 9
    out["velocity"] = rng.integers(20, 128, n)
    for i, k in enumerate(rng.integers(0, len(kinds), n)):
        note, piece, zone, hat = kinds[int(k)]
        out["note"][i], out["instrument"][i] = note, INSTRUMENTS.index(piece)
        out["zone"][i], out["hihat"][i] = ZONES.index(zone), HIHATS.index(hat)
    return out


def live(path: Path, onsets: np.ndarray, n: int, seed: int) -> tuple[np.ndarray, int]:
    """``onsets`` fed to the live mixer as a stream would: each added before the block its
    sample falls in is rendered; blocks of random sizes. Returns the stream and its clip count."""
    from livedrummer.audio.soundfont_live import SoundFontLiveMixer

    rng = np.random.default_rng(seed)
    mixer = SoundFontLiveMixer(path, None, SR)
    parts, pos, i = [], 0, 0
    try:
        while pos < n:
            k = int(min(n - pos, rng.integers(1, 1500)))
            while i < len(onsets) and round(float(onsets["time_s"][i]) * SR) < pos + k + 64:
                mixer.add(onsets[i], round(float(onsets["time_s"][i]) * SR))
                i += 1
            parts.append(mixer.render(k))
            pos += k
    finally:
        mixer.close()
    return np.concatenate(parts), mixer.clipped


@pytest.mark.parametrize("which", ["tiny", "TimGM6mb"])
def test_live_soundfont_is_its_offline_twin(tmp_path: Path, which: str) -> None:
    if which == "tiny":
        path = write_sf2(tmp_path / "tiny.sf2")
    elif TIMGM.is_file():
        path = TIMGM
    else:
        pytest.skip(f"{TIMGM} missing (Debian: timgm6mb-soundfont)")
    onsets = strokes(1)
    seconds = 3.0
    n = round(seconds * SR)
    offline = render_soundfont(onsets, seconds, path, SR)
    online, clipped = live(path, onsets, n, seed=2)
    assert online.shape == offline.shape
    assert float(np.abs(online).max()) > 0.01  # it sounds
    peak = float(np.abs(online).max())
    if clipped == 0 and peak <= 0.9:  # the offline track was not scaled for headroom
        scale = 1.0
    else:  # it was scaled as a whole: compare shapes, at the offline scale
        scale = float(np.abs(offline).max()) / peak
    # FluidSynth renders whole 64-sample blocks whatever the calls ask for, and its reverb and
    # chorus run on its own block count, the same in both: the two agree to float rounding
    err = float(np.sqrt(np.mean((online * scale - offline) ** 2)))
    rms = float(np.sqrt(np.mean(offline**2)))
    print(f"{which}: online - offline RMS {err:.2e} (track RMS {rms:.2e}, scale {scale:.4f})")
    assert err <= 1e-4 * rms, (err, rms)


def test_a_stroke_arriving_late_still_sounds_at_the_next_block(tmp_path: Path) -> None:
    from livedrummer.audio.soundfont_live import SoundFontLiveMixer

    path = write_sf2(tmp_path / "tiny.sf2")
    mixer = SoundFontLiveMixer(path, None, SR)
    try:
        silent = mixer.render(4800)
        mixer.add(strokes(3, n=1)[0], 1000)  # its sample is long gone
        late = mixer.render(4800)
    finally:
        mixer.close()
    assert float(np.abs(silent).max()) < 1e-6  # FluidSynth idles at ~1e-8
    first = int(np.argmax(np.abs(late[:, 0]) > 1e-3))
    assert 0 < float(np.abs(late).max()) and first < 128, first
