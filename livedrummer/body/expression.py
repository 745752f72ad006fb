"""Kinematic expression (SMED §4.1.1), its parameters and its TOML presets.

SMED gives the user an amplitude gain with its distribution over wrist, elbow and shoulder,
a frequency gain with its own distribution, and the amplitudes of back sway and head bob.
A distribution is three shares summing to one; moving one share by A moves the other two by
-A in proportion to their current values (:func:`redistribute`), as SMED's sliders do.

Amplitude scales the preparation/rebound rotation of each joint; frequency shortens the time
from preparation to strike and strike to rebound ("snap"): a joint whose frequency share is
above a third reaches its keys later and leaves them sooner. Beyond SMED's sliders the
expression holds what its users asked for and its animation had built in: how often the
back sways and the head bobs per beat, each piece kind's own amplitude (a hi-hat softer than
the snare), how fast the torso turns, a sideways sway, a head tilt, and the CTB bias of the
arm curves (anticipation below 0, follow-through above).

One table, :data:`PARAMS`, names every parameter with its range, default, unit and meaning:
the TOML keys of a preset, the live parameters (``/livedrummer/param/NAME``), their checks
(:func:`with_param`) and the documentation's table (:func:`params_markdown`) all come from it.
Presets live in ``kits/presets/*.toml`` (one ``[expression]`` table, every key optional,
unknown keys are errors; the shares also as arrays ``amplitude_shares`` and
``frequency_shares``) and are loaded with :func:`load_expression`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from livedrummer.config import Table, read_toml
from livedrummer.errors import PresetError
from livedrummer.kit.catalog import entries, looks_like_path
from livedrummer.kit.lights import LightSpec, light_spec_of, parse_light_spec
from livedrummer.kit.vocabulary import PieceKind

Shares = tuple[float, float, float]  # wrist, elbow, shoulder

#: The piece kinds in the order of :attr:`Expression.piece_amplitude`.
PIECE_KINDS: tuple[str, ...] = tuple(k.value for k in PieceKind)
JOINTS = ("wrist", "elbow", "shoulder")


@dataclass(frozen=True, slots=True)
class Expression:
    amplitude_gain: float = 1.0
    amplitude_shares: Shares = (0.55, 0.25, 0.20)
    frequency_gain: float = 1.0
    frequency_shares: Shares = (1 / 3, 1 / 3, 1 / 3)
    back_amplitude_deg: float = 2.5
    head_amplitude_deg: float = 7.0
    twist_fraction: float = 0.35  # how far the torso turns towards the played piece (0..1)
    back_frequency: float = 1.0  # back sways per beat
    head_frequency: float = 1.0  # head bobs per beat
    turn_speed_deg_s: float = 150.0  # the torso turns at most this fast
    side_sway_deg: float = 0.0  # sideways sway of the back, to one side and the other
    head_tilt_deg: float = 0.0  # the head tilted sideways (positive: to the drummer's right)
    ctb_bias: float = 0.0  # arm curves: < 0 anticipation, > 0 follow-through
    piece_amplitude: tuple[float, ...] = (1.0,) * len(PIECE_KINDS)  # by PIECE_KINDS

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

    def piece_gain(self, kind: str) -> float:
        """The amplitude factor of strokes on a piece of ``kind``."""
        return self.piece_amplitude[PIECE_KINDS.index(kind)]


@dataclass(frozen=True)
class Param:
    """One expression parameter: a preset key and a live parameter."""

    name: str
    lo: float
    hi: float
    default: float
    unit: str
    doc: str


def _params() -> tuple[Param, ...]:
    d = Expression()
    out = [
        Param(
            "amplitude_gain",
            0.0,
            3.0,
            d.amplitude_gain,
            "x",
            "size of every stroke (SMED's amplitude gain)",
        )
    ]
    out += [
        Param(
            f"amplitude_{j}",
            0.0,
            1.0,
            d.amplitude_shares[i],
            "share",
            f"the {j}'s share of the stroke; the other two keep their ratio",
        )
        for i, j in enumerate(JOINTS)
    ]
    out.append(
        Param(
            "frequency_gain",
            0.2,
            5.0,
            d.frequency_gain,
            "x",
            "snap of every stroke (SMED's frequency gain)",
        )
    )
    out += [
        Param(
            f"frequency_{j}",
            0.0,
            1.0,
            d.frequency_shares[i],
            "share",
            f"the {j}'s share of the snap; the other two keep their ratio",
        )
        for i, j in enumerate(JOINTS)
    ]
    out += [
        Param(
            "back_amplitude_deg",
            0.0,
            20.0,
            d.back_amplitude_deg,
            "deg",
            "forward sway of the back on the beat",
        ),
        Param(
            "back_frequency",
            0.25,
            4.0,
            d.back_frequency,
            "per beat",
            "back sways per beat (0.5: every other beat)",
        ),
        Param("head_amplitude_deg", 0.0, 30.0, d.head_amplitude_deg, "deg", "head bob"),
        Param("head_frequency", 0.25, 4.0, d.head_frequency, "per beat", "head bobs per beat"),
        Param(
            "twist_fraction",
            0.0,
            1.0,
            d.twist_fraction,
            "0..1",
            "how far the torso turns towards the piece played",
        ),
        Param(
            "turn_speed_deg_s",
            20.0,
            600.0,
            d.turn_speed_deg_s,
            "deg/s",
            "fastest turn of the torso",
        ),
        Param(
            "side_sway_deg",
            0.0,
            10.0,
            d.side_sway_deg,
            "deg",
            "sideways sway of the back, one side per beat",
        ),
        Param(
            "head_tilt_deg",
            -20.0,
            20.0,
            d.head_tilt_deg,
            "deg",
            "sideways tilt of the head (positive: to the drummer's right)",
        ),
        Param(
            "ctb_bias",
            -0.8,
            0.8,
            d.ctb_bias,
            "-1..1",
            "bias of the arm curves: anticipation below 0, follow-through above",
        ),
    ]
    out += [
        Param(f"amplitude_{k}", 0.0, 2.0, 1.0, "x", f"stroke size on a {k}") for k in PIECE_KINDS
    ]
    return tuple(out)


#: Every expression parameter (see the module docstring).
PARAMS: tuple[Param, ...] = _params()
PARAM_NAMES: dict[str, Param] = {p.name: p for p in PARAMS}


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


def _where(name: str) -> tuple[str, int | None]:
    """The Expression field that parameter ``name`` sets, and its index in a tuple field."""
    head, _, tail = name.partition("_")
    if head in ("amplitude", "frequency") and tail in JOINTS:
        return f"{head}_shares", JOINTS.index(tail)
    if head == "amplitude" and tail in PIECE_KINDS:
        return "piece_amplitude", PIECE_KINDS.index(tail)
    return name, None


def param_value(e: Expression, name: str) -> float:
    """The value of parameter ``name`` in ``e``."""
    field, index = _where(name)
    value = getattr(e, field)
    return float(value[index] if index is not None else value)


def with_param(e: Expression, name: str, value: float) -> Expression:
    """``e`` with parameter ``name`` set to ``value``: a share rescales the other two (see
    :func:`redistribute`). Raises ValueError naming the parameter and its range."""
    p = PARAM_NAMES.get(name)
    if p is None:
        raise ValueError(f"no expression parameter named {name!r}")
    if not (p.lo <= value <= p.hi):  # also NaN
        raise ValueError(f"{name}: expected {p.lo:g}..{p.hi:g} (got {value!r})")
    field, index = _where(name)
    changed: dict[str, object]
    if field.endswith("_shares") and index is not None:
        changed = {field: redistribute(getattr(e, field), index, float(value))}
    elif index is not None:
        old = list(getattr(e, field))
        old[index] = float(value)
        changed = {field: tuple(old)}
    else:
        changed = {field: float(value)}
    return replace(e, **changed)  # type: ignore[arg-type]  # the table names real fields


def params_markdown() -> str:
    """The parameter table of the documentation's presets page (``deploy/docs_hooks.py``)."""
    lines = [
        "| parameter | range | default | unit | what it does |",
        "| --- | --- | --- | --- | --- |",
    ]
    for p in PARAMS:
        lines.append(f"| `{p.name}` | {p.lo:g}..{p.hi:g} | {p.default:.3g} | {p.unit} | {p.doc} |")
    return "\n".join(lines) + "\n"


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
    out = replace(
        d,
        amplitude_shares=_shares(t, "amplitude_shares", d.amplitude_shares),
        frequency_shares=_shares(t, "frequency_shares", d.frequency_shares),
    )
    for p in PARAMS:  # in the table's order: a share given alone rescales the other two
        if t.has(p.name):
            out = with_param(out, p.name, t.number(p.name, lo=p.lo, hi=p.hi))
        else:
            t.number(p.name, p.default)  # marks it known
    t.done()
    if root.has("lights"):  # the show lights a preset brings (preset_lights), checked here too
        parse_light_spec(root.table("lights"))
    root.done()
    return out


def preset_lights(name_or_path: str) -> LightSpec | None:
    """The ``[lights]`` table of a preset (by name or path, as :func:`load_expression`),
    checked; None when it has none."""
    path = _preset_path(name_or_path)
    return light_spec_of(read_toml(path, PresetError), str(path), PresetError)


def expression_to_toml(e: Expression) -> str:
    """A preset file that loads as ``e`` (the shares as arrays, every other parameter)."""
    lines = ["[expression]"]
    for name in ("amplitude_shares", "frequency_shares"):
        lines.append(f"{name} = [{', '.join(repr(float(x)) for x in getattr(e, name))}]")
    for p in PARAMS:
        if _where(p.name)[0].endswith("_shares"):
            continue
        lines.append(f"{p.name} = {param_value(e, p.name)!r}")
    return "\n".join(lines) + "\n"


def load_expression(name_or_path: str) -> Expression:
    """A preset by name (``kits/presets/NAME.toml``) or by path."""
    path = _preset_path(name_or_path)
    return parse_expression(read_toml(path, PresetError), str(path))


def _preset_path(name_or_path: str) -> Path:
    if looks_like_path(name_or_path):
        return Path(name_or_path)
    found = entries("kits/presets")
    if name_or_path not in found:
        known = ", ".join(sorted(found)) or "none"
        raise PresetError(f"no expression preset named {name_or_path!r} (known: {known})")
    return found[name_or_path].path
