"""The show's settings, resolved once by the launcher and handed to every process whole.

A live rig is several processes (input daemon, synth, display; :mod:`services.process.supervisor`)
that must agree on what they play: the note map that turns MIDI notes into pieces, the kit,
the avatar and how it is fitted, the show delay D and the lookahead L, and the sound. When
each process derived these from its own flags and defaults they drifted (``up --keys`` gave
its children the General MIDI map but mixed its own recording's drum track with the Roland
one). So the launcher (``up``, ``up --stage``, ``practice --show``) resolves them here once,
into :class:`ShowSettings`, writes that as one JSON file, and gives every child the file
(``--settings FILE``); a child takes what the file says and derives nothing. Run alone, a
service builds the same object from its own flags, so both paths meet in one type.

The file is JSON: ``{"format": "livedrummer-show-settings", "version": 1, "note_map": ...,
"kit": ..., "avatar": {...}, "delay": {...}, "sound": {...}}`` (``docs/config.md``). It is
read strictly through :class:`~livedrummer.config.Table` like every TOML file here: a key
nobody reads is refused with its name and a "did you mean", a bad value is one line naming the
file and the field. :meth:`ShowSettings.to_dict` and :meth:`ShowSettings.from_dict` round-trip
exactly, so TOML (``tomllib`` reads it into the same dict) would do as well as JSON.

The delay rule ``0 <= L <= D`` (a note's hand is decided before its contact is shown) is
checked in :func:`check_delay` alone: the launcher, a service's flags, a settings file and
:class:`~livedrummer.live.synth.SynthParams` all reach it, each naming its own fields.

Limits: a kit, map or avatar is kept as its name or path (resolved to an absolute path when it
is a file), not its contents: a child loads it, so a file edited between the launcher's check
and the child's start is read as it is then. The stage display reads each performer's kit and
avatar from the stage file itself.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from livedrummer.config import Table
from livedrummer.errors import ConfigError

FORMAT = "livedrummer-show-settings"
VERSION = 1
AUTO = "auto"  # a map chosen by the notes: never in a resolved file
FITS = ("auto", "avatar", "kit", "none")  # as livedrummer.avatar.fit.FITS


class SettingsError(ConfigError):
    """A resolved settings file (or the values it would hold) is malformed or inconsistent."""


class DelayError(SettingsError, ValueError):
    """The lookahead L and show delay D break ``0 <= L <= D`` (also a ValueError, as the
    synth's parameters have always raised it)."""


def check_delay(
    lookahead_s: float, delay_s: float, names: tuple[str, str] = ("lookahead_ms", "delay_ms")
) -> None:
    """The one check of the show delay: finite, and ``0 <= L <= D``; ``names`` are the two
    fields as the caller's user wrote them (flags, file keys)."""
    lk, dl = names
    for name, value in ((lk, lookahead_s), (dl, delay_s)):
        if not math.isfinite(value):
            raise DelayError(f"{name} {value * 1000:g}: expected a finite number of ms")
    if not 0.0 <= lookahead_s <= delay_s:
        raise DelayError(
            f"{lk} {lookahead_s * 1000:g} must be between 0 and {dl} {delay_s * 1000:g} "
            "(a note is decided before it shows)"
        )


@dataclass(frozen=True)
class Delay:
    """The show delay D (the drummer is shown D behind the sound) and the lookahead L (limb
    decisions wait L for later notes), in seconds."""

    lookahead_s: float = 0.030
    delay_s: float = 0.030

    def __post_init__(self) -> None:
        check_delay(self.lookahead_s, self.delay_s)

    @classmethod
    def from_ms(
        cls, lookahead_ms: float, delay_ms: float, names: tuple[str, str] | None = None
    ) -> Delay:
        """From milliseconds as flags and files give them; an error names ``names``."""
        if names is not None:
            check_delay(lookahead_ms / 1000.0, delay_ms / 1000.0, names)
        return cls(lookahead_ms / 1000.0, delay_ms / 1000.0)


@dataclass(frozen=True)
class AvatarChoice:
    """Who plays: an avatar file or name (None: the built-in character), its bone map, and
    how it is fitted to the kit (one of :data:`FITS`)."""

    spec: str | None = None
    bone_map: str | None = None
    fit: str = "auto"

    def __post_init__(self) -> None:
        if self.fit not in FITS:
            raise SettingsError(f"avatar fit {self.fit!r}: expected one of {', '.join(FITS)}")


@dataclass(frozen=True)
class Sound:
    """Whether the display sounds each onset at onset + D, from which kit file (an SF2 or SFZ;
    None: the built-in kit) and on which output (None: the system's default). The kit file is
    also what a recording's drum track is mixed with."""

    on: bool = False
    kit_file: str | None = None
    device: str | None = None


@dataclass(frozen=True)
class ShowSettings:
    """Everything the processes of one drummer's rig must agree on (see the module docstring).

    ``note_map`` is a map name or an absolute ``.toml`` path, never ``auto``: choosing a map
    by the notes is the launcher's job, done before this is made.
    """

    note_map: str
    kit: str = "rock5"
    avatar: AvatarChoice = field(default_factory=AvatarChoice)
    delay: Delay = field(default_factory=Delay)
    sound: Sound = field(default_factory=Sound)

    def __post_init__(self) -> None:
        if not self.note_map or self.note_map == AUTO:
            raise SettingsError(
                f"note_map {self.note_map!r}: a resolved map is a name or a file, not auto"
            )
        if not self.kit:
            raise SettingsError("kit: expected a kit name or file (got '')")

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready form; :meth:`from_dict` reads it back equal. Absent values are left
        out (JSON has null, TOML does not)."""

        def some(**kv: Any) -> dict[str, Any]:
            return {k: v for k, v in kv.items() if v is not None}

        return {
            "format": FORMAT,
            "version": VERSION,
            "note_map": self.note_map,
            "kit": self.kit,
            "avatar": some(
                spec=self.avatar.spec, bone_map=self.avatar.bone_map, fit=self.avatar.fit
            ),
            "delay": {
                "lookahead_ms": self.delay.lookahead_s * 1000.0,
                "delay_ms": self.delay.delay_s * 1000.0,
            },
            "sound": some(on=self.sound.on, kit_file=self.sound.kit_file, device=self.sound.device),
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, sort_keys=True) + "\n"

    def digest(self) -> str:
        """A short hash of the settings: equal in every process given the same settings."""
        canon = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(canon.encode()).hexdigest()[:12]

    def summary(self) -> dict[str, Any]:
        """What a service reports of its settings in its ready line (map, kit, D, L, digest)."""
        return {
            "map": self.note_map,
            "kit": self.kit,
            "delay_ms": round(self.delay.delay_s * 1000.0, 6),
            "lookahead_ms": round(self.delay.lookahead_s * 1000.0, 6),
            "digest": self.digest(),
        }

    @classmethod
    def from_dict(cls, data: object, source: str) -> ShowSettings:
        """Read a dict as :meth:`to_dict` writes it; unknown keys and bad values are one
        :class:`SettingsError` naming ``source`` and the field."""
        top = Table(data, source, "", SettingsError)
        fmt = top.text("format")
        if fmt != FORMAT:
            raise top.fail("format", f"expected {FORMAT!r}", fmt)
        version = top.integer("version")
        if version != VERSION:
            raise top.fail("version", f"this livedrummer reads version {VERSION}", version)
        note_map = top.text("note_map")
        kit = top.text("kit")
        av = top.table("avatar", None) or Table({}, source, "avatar", SettingsError)
        spec = av.text("spec", None)
        bone_map = av.text("bone_map", None)
        fit = av.text("fit", "auto", choices=FITS)
        av.done()
        dl = top.table("delay")
        lookahead_ms = dl.number("lookahead_ms", lo=0.0)
        delay_ms = dl.number("delay_ms", lo=0.0)
        dl.done()
        try:
            check_delay(lookahead_ms / 1000.0, delay_ms / 1000.0)
        except DelayError as exc:
            raise SettingsError(f"{source}: [delay] {exc}") from None
        sd = top.table("sound", None) or Table({}, source, "sound", SettingsError)
        sound = Sound(sd.boolean("on", False), sd.text("kit_file", None), sd.text("device", None))
        sd.done()
        top.done()
        try:
            return cls(
                note_map,
                kit,
                AvatarChoice(spec, bone_map, fit),
                Delay.from_ms(lookahead_ms, delay_ms),
                sound,
            )
        except SettingsError as exc:
            raise SettingsError(f"{source}: {exc}") from None

    @classmethod
    def from_json(cls, text: str, source: str) -> ShowSettings:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise SettingsError(f"{source}: line {exc.lineno}: not JSON ({exc.msg})") from None
        return cls.from_dict(data, source)

    @classmethod
    def load(cls, path: Path) -> ShowSettings:
        """Read a settings file that a launcher wrote (:meth:`save`)."""
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            raise SettingsError(f"{path}: cannot read the settings file: {why}") from None
        return cls.from_json(text, str(path))

    def save(self, path: Path) -> Path:
        path.write_text(self.to_json(), encoding="utf-8")
        return path


def spec_path(spec: str | None) -> str | None:
    """A kit, map or avatar spec as a child process should see it: a file that exists as its
    absolute path (the child may run elsewhere), a name unchanged."""
    if spec is None:
        return None
    path = Path(spec)
    if path.suffix and path.exists():
        return str(path.resolve())
    return spec
