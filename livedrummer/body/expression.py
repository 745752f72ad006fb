"""Kinematic expression (SMED §4.1.1) and its TOML presets.

SMED gives the user an amplitude gain with its distribution over wrist, elbow and shoulder,
a frequency gain with its own distribution, and the amplitudes of back sway and head bob.
A distribution is three shares summing to one; moving one share by A moves the other two by
-A in proportion to their current values (:func:`redistribute`), as SMED's sliders do.

Amplitude scales the preparation/rebound rotation of each joint; frequency shortens the time
from preparation to strike and strike to rebound ("snap"): a joint whose frequency share is
above a third reaches its keys later and leaves them sooner. Presets live in
``kits/presets/*.toml`` (one ``[expression]`` table, every key optional, unknown keys are
errors) and are loaded with :func:`load_expression`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from livedrummer.config import Table, read_toml
from livedrummer.errors import PresetError
from livedrummer.kit.catalog import entries, looks_like_path

Shares = tuple[float, float, float]  # wrist, elbow, shoulder


@dataclass(frozen=True, slots=True)
class Expression:
    amplitude_gain: float = 1.0
    amplitude_shares: Shares = (0.55, 0.25, 0.20)
    frequency_gain: float = 1.0
    frequency_shares: Shares = (1 / 3, 1 / 3, 1 / 3)
    back_amplitude_deg: float = 2.5
    head_amplitude_deg: float = 7.0
    twist_fraction: float = 0.35  # how far the torso turns towards the played piece (0..1)

    def joint_amplitude_rad(self, full_rad: float) -> Shares:
        """Preparation rotation (radians) of wrist, elbow and shoulder at full velocity."""
        w, e, s = self.amplitude_shares
        g = self.amplitude_gain * full_rad
        return (g * w, g * e, g * s)

    def joint_time_scale(self) -> Shares:
        """Factor (<= 1) on the preparation/rebound offsets of wrist, elbow and shoulder."""
        out = [
            min(1.0, 1.0 / max(self.frequency_gain * 3.0 * share, 1e-6))
            for share in self.frequency_shares
        ]
        return (out[0], out[1], out[2])


def redistribute(shares: Shares, index: int, value: float) -> Shares:
    """Set share ``index`` to ``value`` and rescale the other two to keep their ratio."""
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"share must be in [0, 1], got {value}")
    others = [i for i in range(3) if i != index]
    rest = sum(shares[i] for i in others)
    out = list(shares)
    out[index] = value
    for i in others:
        out[i] = (1.0 - value) * (shares[i] / rest if rest > 0 else 0.5)
    return (out[0], out[1], out[2])


def _shares(table: Table, key: str, default: Shares) -> Shares:
    if not table.has(key):
        table.vector(key, 3, default)  # marks it used
        return default
    v = table.vector(key, 3)
    if any(x < 0 for x in v) or abs(sum(v) - 1.0) > 1e-3:
        raise table.fail(key, "three non-negative shares summing to 1", list(v))
    return (float(v[0]), float(v[1]), float(v[2]))


def parse_expression(data: dict[str, object], source: str) -> Expression:
    root = Table(data, source, "", PresetError)
    t = root.table("expression")
    d = Expression()
    out = Expression(
        amplitude_gain=t.number("amplitude_gain", d.amplitude_gain, lo=0.0, hi=3.0),
        amplitude_shares=_shares(t, "amplitude_shares", d.amplitude_shares),
        frequency_gain=t.number("frequency_gain", d.frequency_gain, lo=0.2, hi=5.0),
        frequency_shares=_shares(t, "frequency_shares", d.frequency_shares),
        back_amplitude_deg=t.number("back_amplitude_deg", d.back_amplitude_deg, lo=0.0, hi=20.0),
        head_amplitude_deg=t.number("head_amplitude_deg", d.head_amplitude_deg, lo=0.0, hi=30.0),
        twist_fraction=t.number("twist_fraction", d.twist_fraction, lo=0.0, hi=1.0),
    )
    t.done()
    root.done()
    return out


def expression_to_toml(e: Expression) -> str:
    lines = ["[expression]"]
    for f in fields(e):
        v = getattr(e, f.name)
        text = f"[{', '.join(repr(float(x)) for x in v)}]" if isinstance(v, tuple) else repr(v)
        lines.append(f"{f.name} = {text}")
    return "\n".join(lines) + "\n"


def load_expression(name_or_path: str) -> Expression:
    """A preset by name (``kits/presets/NAME.toml``) or by path."""
    if looks_like_path(name_or_path):
        path = Path(name_or_path)
    else:
        found = entries("kits/presets")
        if name_or_path not in found:
            known = ", ".join(sorted(found)) or "none"
            raise PresetError(f"no expression preset named {name_or_path!r} (known: {known})")
        path = found[name_or_path].path
    return parse_expression(read_toml(path, PresetError), str(path))
