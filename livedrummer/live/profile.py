"""The rig profile: one file that says how this machine's show runs (``rig.toml``).

A show technician sets a rig up once: which kit module or trigger board, which kit, note
map and avatar, which camera on which projector, the visual delay, the endpoints. ``up``
reads ``$LIVEDRUMMER_HOME/rig.toml`` (or ``up --rig FILE``) and takes every value there as
the default of the option of the same name, so ``up`` alone starts the show and any option
on the command line still wins; ``livedrummer deploy systemd`` writes a user unit that runs
exactly that at boot. The file is read strictly (:mod:`livedrummer.config`): an unknown key
or a bad value is one line naming the file, the table and the key. Example::

    [source]            # one of midi, serial or demo
    midi = "TD-17"
    api = "auto"        # or baud = 31250 with serial = "/dev/ttyACM0"

    [show]
    kit = "rock5"
    map = "roland-td"
    avatar = "my.vrm"
    camera = "front"
    fullscreen = true
    monitor = 1
    size = "1280x720"
    fps = 60
    delay_ms = 30
    lookahead_ms = 30

    [network]
    port_base = 5710
    bind = "127.0.0.1"

Limits: one performer per profile; the CURVE key files of a remote rig stay options.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError
from livedrummer.resources import user_home

FILE_NAME = "rig.toml"


class RigProfileError(ConfigError):
    """``rig.toml`` cannot be read or holds a bad value."""


@dataclass(frozen=True)
class RigProfile:
    """Option name (as ``up`` spells its destination) -> value, and where it came from."""

    path: Path
    options: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def load(cls, path: Path) -> RigProfile:
        data = read_toml(path, RigProfileError)
        top = Table(data, str(path), "", RigProfileError)
        options: dict[str, Any] = {}

        def section(name: str) -> Table:
            found = top.table(name, None)
            return found if found is not None else Table({}, str(path), name, RigProfileError)

        src = section("source")
        given = [k for k in ("midi", "serial", "demo") if src.has(k)]
        if len(given) > 1:
            raise src.fail(given[1], f"give one source of midi, serial, demo (also {given[0]})")
        if src.has("midi"):
            options["midi"] = src.text("midi")
        if src.has("serial"):
            options["serial"] = src.text("serial")
        if src.has("demo"):
            options["demo"] = src.boolean("demo")
        if src.has("api"):
            options["api"] = src.text("api", choices=("auto", "jack", "alsa"))
        if src.has("baud"):
            options["baud"] = src.integer("baud", lo=1)
        src.done()
        show = section("show")
        for key in ("kit", "map", "avatar", "camera", "size"):
            if show.has(key):
                options[key] = show.text(key)
        for key in ("fullscreen", "headless"):
            if show.has(key):
                options[key] = show.boolean(key)
        if show.has("monitor"):
            options["monitor"] = show.integer("monitor", lo=0, hi=16)
        if show.has("fps"):
            options["fps"] = show.number("fps", lo=1.0, hi=1000.0)
        for key in ("delay_ms", "lookahead_ms"):
            if show.has(key):
                options[key] = show.number(key, lo=0.0, hi=2000.0)
        show.done()
        net = section("network")
        if net.has("port_base"):
            options["port_base"] = net.integer("port_base", lo=1, hi=65535 - 11)
        if net.has("bind"):
            options["bind"] = net.text("bind")
        net.done()
        top.done()
        return cls(path, options)


def default_path() -> Path:
    return user_home() / FILE_NAME
