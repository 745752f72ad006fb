"""Calibration offsets for input, audio and display, persisted in ``calibration.toml``.

Rhythm-game players tune these separately, and so does a stage rig: the *input* offset is
added to every onset's arrival time (a kit's own trigger latency), the *audio* offset to the
audio clock the display follows (the sound card's latency beyond what it reports), and the
*display* offset to the time a frame is rendered for (a projector's processing delay). All
in milliseconds, each within ±500 ms. The file lives in ``$LIVEDRUMMER_HOME`` and is read
strictly (unknown keys refused with their name); a missing file means zero offsets.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError
from livedrummer.resources import user_home

FILE_NAME = "calibration.toml"
LIMIT_MS = 500.0


class CalibrationError(ConfigError):
    """``calibration.toml`` cannot be read or holds a bad value."""


@dataclass(frozen=True)
class Calibration:
    input_ms: float = 0.0
    audio_ms: float = 0.0
    display_ms: float = 0.0

    @classmethod
    def load(cls, path: Path | None = None) -> Calibration:
        path = path if path is not None else default_path()
        if not path.exists():
            return cls()
        table = Table(read_toml(path, CalibrationError), str(path), "", CalibrationError)
        out = cls(
            input_ms=table.number("input_ms", 0.0, -LIMIT_MS, LIMIT_MS),
            audio_ms=table.number("audio_ms", 0.0, -LIMIT_MS, LIMIT_MS),
            display_ms=table.number("display_ms", 0.0, -LIMIT_MS, LIMIT_MS),
        )
        table.done()
        return out

    def save(self, path: Path | None = None) -> Path:
        path = path if path is not None else default_path()
        text = (
            "# livedrummer calibration offsets, milliseconds\n"
            f"input_ms = {self.input_ms!r}\n"
            f"audio_ms = {self.audio_ms!r}\n"
            f"display_ms = {self.display_ms!r}\n"
        )
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp")
            tmp.write_text(text)
            tmp.replace(path)
        except OSError as exc:
            raise CalibrationError(f"{path}: cannot write: {exc.strerror or exc}") from exc
        return path


def default_path() -> Path:
    return user_home() / FILE_NAME
