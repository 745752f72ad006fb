"""MIDI controller mappings: faders, knobs and pads of a control surface steering the show.

A mapping file (written by ``livedrummer control learn``, read by ``up --control FILE``)
binds a controller (``cc = N``) or a pad (``note = N``), on one channel or any, to a target::

    [[control]]
    cc = 7
    channel = 1                       # 1-16; leave out for any channel
    param = "head_amplitude_deg"      # the fader sweeps the parameter's whole range

    [[control]]
    note = 36
    camera = "front"                  # or cut = NAME, cue = NAME, preset = NAME

    [[control]]
    note = 37
    blackout = true                   # a pad toggles the blackout; a cc holds it (>= 64)

Why this shape. A binding turns a MIDI message into the same OSC command a cue desk would
send (:meth:`ControlMap.commands` gives address and arguments), so a controller steers the
show through the one routing of :mod:`services.show.osc` and a mapping can be checked without
any device. The one table :data:`TARGETS` names the targets, what they take and their OSC
address.

Limits: a parameter needs a controller (a pad has no range); 7-bit values only (no 14-bit
controller pairs, no NRPN); a pad acts on note-on, its release is ignored.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from livedrummer.body.expression import PARAM_NAMES, load_expression
from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError, LivedrummerError
from livedrummer.live.stage import camera_name

#: target -> (what it takes, its OSC address; a parameter's name is appended)
TARGETS: dict[str, tuple[str, str]] = {
    "param": ("an expression parameter name", "/livedrummer/param/"),
    "camera": ("a camera name or 1-8", "/livedrummer/camera"),
    "cut": ("a camera name or 1-8", "/livedrummer/camera/cut"),
    "cue": ("a cue name", "/livedrummer/cue"),
    "preset": ("a preset name or .toml path", "/livedrummer/preset"),
    "blackout": ("true", "/livedrummer/blackout"),
}

Command = tuple[str, tuple[str | float | int, ...]]


class ControlMapError(ConfigError):
    """A mapping that cannot be used (file, control and key named)."""


@dataclass(frozen=True)
class Binding:
    kind: str  # "cc" or "note"
    number: int  # 0..127
    channel: int | None  # 0..15, None: any
    target: str  # a key of TARGETS
    value: str  # the parameter, camera, cue or preset ("" for the blackout)


def check_target(target: str, value: str, kind: str) -> str:
    """``value`` checked for ``target``; ValueError naming what is expected."""
    if target not in TARGETS:
        raise ValueError(f"target {target!r}: expected one of {', '.join(TARGETS)}")
    if target == "param":
        if kind != "cc":
            raise ValueError("a parameter needs a controller (cc), not a pad")
        if value not in PARAM_NAMES:
            raise ValueError(f"no expression parameter named {value!r}")
        return value
    if target in ("camera", "cut"):
        return camera_name(value)
    if target == "preset":
        try:
            load_expression(value)
        except LivedrummerError as exc:
            raise ValueError(str(exc)) from None
    if target == "cue" and not value:
        raise ValueError("a cue needs its name")
    return "" if target == "blackout" else value


class ControlMap:
    """Bindings, and the state a pad toggles (see the module docstring)."""

    def __init__(self, bindings: list[Binding]) -> None:
        self.bindings = bindings
        self.blackout = False

    def commands(self, kind: str, channel: int, number: int, value: int) -> list[Command]:
        """The OSC commands one MIDI message means: ``kind`` "cc" (``value`` 0..127) or
        "note" (``value`` the velocity; 0 is a release); channel 0..15."""
        out: list[Command] = []
        for b in self.bindings:
            if b.kind != kind or b.number != number or b.channel not in (None, channel):
                continue
            address = TARGETS[b.target][1]
            if b.target == "param":
                p = PARAM_NAMES[b.value]
                out.append((address + b.value, (p.lo + (p.hi - p.lo) * value / 127.0,)))
            elif b.target == "blackout":
                if kind == "note":
                    if value == 0:
                        continue
                    self.blackout = not self.blackout
                else:
                    self.blackout = value >= 64
                out.append((address, (int(self.blackout),)))
            elif (kind == "cc" and value < 64) or (kind == "note" and value == 0):
                continue  # a button's release, a fader below half way
            else:
                out.append((address, (b.value,)))
        return out

    def toml(self) -> str:
        lines = ["# livedrummer control map: up --control FILE --control-midi PORT"]
        for b in self.bindings:
            lines += ["", "[[control]]", f"{b.kind} = {b.number}"]
            if b.channel is not None:
                lines.append(f"channel = {b.channel + 1}")
            value = "true" if b.target == "blackout" else f'"{b.value}"'
            lines.append(f"{b.target} = {value}")
        return "\n".join(lines) + "\n"


def parse_control_map(data: dict[str, object], source: str) -> ControlMap:
    root = Table(data, source, "", ControlMapError)
    out: list[Binding] = []
    for t in root.tables("control"):
        kinds = [k for k in ("cc", "note") if t.has(k)]
        if len(kinds) != 1:
            raise t.fail(None, "give cc = N or note = N (one of them)")
        kind = kinds[0]
        number = t.integer(kind, lo=0, hi=127)
        channel = t.integer("channel", None, lo=1, hi=16)
        targets = [k for k in TARGETS if t.has(k)]
        if len(targets) != 1:
            raise t.fail(None, f"give one target: {', '.join(TARGETS)}")
        target = targets[0]
        if target == "blackout":
            if t.boolean(target) is not True:
                raise t.fail(target, "expected true")
            raw = ""
        elif target in ("camera", "cut"):
            try:
                raw = t.text(target)
            except ControlMapError:
                raw = str(t.integer(target, lo=1, hi=8))
        else:
            raw = t.text(target)
        try:
            value = check_target(target, raw, kind)
        except ValueError as exc:
            raise t.fail(target, str(exc)) from None
        t.done()
        out.append(Binding(kind, number, None if channel is None else channel - 1, target, value))
    root.done()
    return ControlMap(out)


def load_control_map(path: Path | str) -> ControlMap:
    return parse_control_map(read_toml(Path(path), ControlMapError), str(path))
