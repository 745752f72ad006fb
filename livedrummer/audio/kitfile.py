"""A drum track from a kit file: a General MIDI SoundFont (.sf2, FluidSynth) or an SFZ kit
(.sfz, :mod:`~livedrummer.audio.sfz_render`), chosen by the file's suffix, so every command
that takes ``--soundfont`` takes ``--sfz`` the same way and the renderers stay apart."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from livedrummer.audio.synth import SAMPLE_RATE
from livedrummer.kit.model import Kit


def is_sfz(path: Path) -> bool:
    return path.suffix.lower() == ".sfz"


def check_kit_file(path: Path) -> None:
    """Raise the renderer's one-line error now when ``path`` cannot be played."""
    if is_sfz(path):
        from livedrummer.audio.sfz_render import check_sfz

        check_sfz(path)
    else:
        from livedrummer.audio.soundfont import check_soundfont

        check_soundfont(path)


def render_kit_file(
    onsets: np.ndarray,
    duration_s: float,
    path: Path,
    sr: int = SAMPLE_RATE,
    kit: Kit | None = None,
    chokes: Sequence[np.ndarray] | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """``onsets`` played on the kit file ``path`` (see the module docstring)."""
    if is_sfz(path):
        from livedrummer.audio.sfz_render import render_sfz

        return render_sfz(onsets, duration_s, path, sr, kit, chokes, out)
    from livedrummer.audio.soundfont import render_soundfont

    return render_soundfont(onsets, duration_s, path, sr, kit, chokes, out)
