"""An audio profile: a kit's spectral templates, level calibration and detector settings.

A profile is what :func:`~livedrummer.acoustic.detector.detect` knows of a kit's sound: for each
drum class, one or more *templates* (the band spectrum an isolated hit adds in its first few
milliseconds, :data:`~livedrummer.acoustic.spectrum.N_BANDS` numbers, normalised to sum 1) and
the *level* of a full-strength hit (the activation a velocity-127 hit gives; velocities are
read against it). ``livedrummer audio learn`` writes one from the player's own hits; without
one, the bundled ``general-midi`` profile (``kits/audio/general-midi.toml``, made from
isolated hits of a General MIDI SoundFont, so no SoundFont is needed at run time) is used.

Strict TOML like kits (:mod:`livedrummer.config`): unknown keys, wrong lengths and negative
template values are errors naming the file and key::

    name = "mykit"
    [detector]
    delta = 0.9          # onset threshold above the moving mean (log-flux units)
    floor = 2.0          # and an absolute minimum
    [piece.kick]
    level = 41.5
    templates = [[...28 numbers...], ...]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.spectrum import N_BANDS
from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError
from livedrummer.resources import search_dirs


class AudioProfileError(ConfigError):
    """An audio profile file is wrong, or a profile name is unknown."""


@dataclass(frozen=True)
class DetectorSettings:
    """Onset picking and classification settings (see :mod:`.detector`)."""

    delta: float = 2.0  # onset-function units above the moving mean
    floor: float = 3.0  # minimum onset-function value of an onset
    poly: float = 0.2  # a class sounds if its activation is this share of its full-strength level
    min_level: float = 0.02  # activation below which a class is not reported
    offset_ms: float = 3.0  # frame end to attack, subtracted from onset times
    leak: float = 0.15  # multi-mic: largest crosstalk amplitude ratio between two channels
    lookahead: int = 2  # frames (of 128 samples) after the onset frame before deciding


@dataclass(frozen=True)
class AudioProfile:
    """Templates (K, N_BANDS) with their class codes (K,), a level per class, settings."""

    name: str
    templates: np.ndarray
    template_class: np.ndarray
    levels: np.ndarray  # (len(CLASSES),): activation of a full-strength hit; 0 = unknown
    settings: DetectorSettings = field(default_factory=DetectorSettings)

    def to_toml(self) -> str:
        s = self.settings
        lines = [f'name = "{self.name}"', "", "[detector]"]
        for key in ("delta", "floor", "poly", "min_level", "offset_ms", "leak"):
            lines.append(f"{key} = {float(getattr(s, key))!r}")
        lines.append(f"lookahead = {s.lookahead}")
        for code, cls in enumerate(CLASSES):
            rows = self.templates[self.template_class == code]
            if not len(rows):
                continue
            lines += ["", f"[piece.{cls}]", f"level = {float(self.levels[code]):.6g}"]
            lines.append("templates = [")
            for row in rows:
                lines.append("  [" + ", ".join(f"{float(v):.5g}" for v in row) + "],")
            lines.append("]")
        return "\n".join(lines) + "\n"


def parse_profile(data: dict[str, object], source: str) -> AudioProfile:
    top = Table(data, source, "", AudioProfileError)
    name = top.text("name", Path(source).stem)
    det = top.table("detector", {})
    if isinstance(det, Table):
        defaults = DetectorSettings()
        settings = DetectorSettings(
            delta=det.number("delta", defaults.delta, lo=0.0),
            floor=det.number("floor", defaults.floor, lo=0.0),
            poly=det.number("poly", defaults.poly, lo=0.0, hi=1.0),
            min_level=det.number("min_level", defaults.min_level, lo=0.0),
            offset_ms=det.number("offset_ms", defaults.offset_ms, lo=-50.0, hi=50.0),
            leak=det.number("leak", defaults.leak, lo=0.0, hi=1.0),
            lookahead=det.integer("lookahead", defaults.lookahead, lo=1, hi=16),
        )
        det.done()
    else:
        settings = DetectorSettings()
    pieces = top.table("piece")
    templates: list[np.ndarray] = []
    owners: list[int] = []
    levels = np.zeros(len(CLASSES))
    for cls in pieces.keys():
        if cls not in CLASSES:
            raise pieces.fail(cls, f"unknown drum (one of {', '.join(CLASSES)})")
        t = pieces.table(cls)
        code = CLASSES.index(cls)
        levels[code] = t.number("level", lo=0.0)
        rows = t._get("templates", None)  # a list of lists: checked here
        if not isinstance(rows, list) or not rows:
            raise t.fail("templates", "expected a non-empty list of lists", rows)
        for row in rows:
            if not isinstance(row, list) or len(row) != N_BANDS:
                raise t.fail("templates", f"each template is a list of {N_BANDS} numbers", row)
            values = np.array([t._check_number("templates", v, 0.0, None) for v in row])
            if values.sum() <= 0:
                raise t.fail("templates", "a template is all zeros")
            templates.append(values / values.sum())
            owners.append(code)
        t.done()
    top.done()
    if not templates:
        raise AudioProfileError(f"{source}: [piece]: no drums")
    return AudioProfile(name, np.array(templates), np.array(owners, np.int64), levels, settings)


def load_profile(spec: str | Path | None) -> AudioProfile:
    """A profile by path (``*.toml``), by name (``kits/audio/NAME.toml`` in the search
    folders), or the bundled ``general-midi`` for ``None``."""
    spec = "general-midi" if spec is None else spec
    path = Path(spec)
    if path.suffix != ".toml":
        found = [d / f"{spec}.toml" for d in search_dirs("kits/audio")]
        hits = [p for p in found if p.is_file()]
        if not hits:
            names = sorted(
                {p.stem for d in search_dirs("kits/audio") if d.is_dir() for p in d.glob("*.toml")}
            )
            raise AudioProfileError(
                f"audio profile {spec!r} not found (known: {', '.join(names) or 'none'})"
            )
        path = hits[-1]
    elif not path.exists():
        raise AudioProfileError(f"{path}: no such file")
    return parse_profile(read_toml(path, AudioProfileError), str(path))
