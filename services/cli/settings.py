"""``--settings FILE``: a service takes the show's settings its launcher resolved, whole.

``up``, ``up --stage`` and ``practice --show`` resolve the note map, kit, avatar, delay D,
lookahead L and sound once (:class:`~livedrummer.live.settings.ShowSettings`), write them into
one JSON file and start each child with ``--settings FILE`` instead of the separate flags. A
child given the file reads every one of these from it and from nowhere else: a flag of the
same meaning given beside it is refused (one line, exit 2), since two sources for one value is
how the processes drifted apart. Without ``--settings`` a service builds the same object from
its own flags (:func:`settings_of`), so running it alone works as it always has. Each service
reports :meth:`~livedrummer.live.settings.ShowSettings.summary` in its ready line, so a
launcher or a test can see that all of them hold the same.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from livedrummer.avatar.model import Avatar
    from livedrummer.kit.model import Kit
    from livedrummer.live.settings import ShowSettings

#: The flags a settings file replaces, by argparse destination.
FLAGS = {
    "map": "--map", "kit": "--kit", "avatar": "--avatar", "bone_map": "--bone-map",
    "fit": "--fit", "lookahead_ms": "--lookahead-ms", "delay_ms": "--delay-ms",
    "sound": "--sound", "soundfont": "--soundfont/--sfz", "audio_device": "--audio-device",
}  # fmt: skip
SETTINGS_FILE = "settings.json"


def add_settings_option(p: argparse.ArgumentParser) -> None:
    """``--settings FILE``; call it after every other option, so that the defaults of those it
    replaces are known (a flag left at its default is not "given")."""
    p.add_argument(
        "--settings",
        type=Path,
        metavar="FILE",
        help="the show's settings as a launcher (up) resolved them, JSON: map, kit, "
        "avatar, delay, lookahead and sound come from FILE, not from flags "
        "(default: from this command's flags)",
    )
    defaults = {a.dest: a.default for a in p._actions if a.dest in FLAGS}
    p.set_defaults(settings_defaults=defaults)


def given_beside(args: argparse.Namespace, skip: tuple[str, ...] = ()) -> list[str]:
    """The flags set on the command line that ``--settings`` replaces."""
    defaults: dict[str, Any] = getattr(args, "settings_defaults", {})
    return [FLAGS[d] for d, v in defaults.items() if d not in skip and getattr(args, d) != v]


def settings_of(
    args: argparse.Namespace, note_map: str, skip: tuple[str, ...] = ()
) -> ShowSettings:
    """The settings this service plays with: ``--settings FILE`` as it is, or else its own
    flags (``note_map`` is the map it chose; the flags it lacks take their defaults). ``skip``
    names destinations that mean something else here (a practice display's ``--map``)."""
    from livedrummer.errors import ConfigError
    from livedrummer.live.settings import AvatarChoice, Delay, ShowSettings, Sound

    path: Path | None = getattr(args, "settings", None)
    if path is not None:
        given = given_beside(args, skip)
        if given:
            raise ConfigError(
                f"--settings {path}: {', '.join(given)} given beside it; the "
                "file holds them (give one or the other)"
            )
        return ShowSettings.load(path)
    delay = Delay()
    if hasattr(args, "delay_ms"):
        delay = Delay.from_ms(args.lookahead_ms, args.delay_ms, ("--lookahead-ms", "--delay-ms"))
    bone_map = getattr(args, "bone_map", None)
    soundfont = getattr(args, "soundfont", None)
    return ShowSettings(
        note_map=note_map,
        kit=getattr(args, "kit", "rock5"),
        avatar=AvatarChoice(
            getattr(args, "avatar", None),
            None if bone_map is None else str(bone_map),
            getattr(args, "fit", "auto"),
        ),
        delay=delay,
        sound=Sound(
            bool(getattr(args, "sound", False)),
            None if soundfont is None else str(soundfont),
            getattr(args, "audio_device", None),
        ),
    )


def write_settings(settings: ShowSettings, folder: Path, name: str = SETTINGS_FILE) -> Path:
    """The file a launcher hands its children (``--settings``)."""
    return settings.save(folder / name)


def avatar_from(settings: ShowSettings) -> Avatar | None:
    """The avatar the settings name, loaded and bound to the body (None: the built-in one)."""
    if settings.avatar.spec is None:
        return None
    from livedrummer.avatar.loader import load_avatar

    bone_map = settings.avatar.bone_map
    return load_avatar(settings.avatar.spec, None if bone_map is None else Path(bone_map))


def played_by(settings: ShowSettings) -> tuple[Kit, Avatar | None]:
    """The kit and avatar to play, fitted as the settings say (:func:`~livedrummer.avatar.fit.
    fit_avatar`); with an avatar, one line on stderr says how it was fitted."""
    from livedrummer.avatar.fit import fit_avatar
    from livedrummer.kit.loader import load_kit

    avatar = avatar_from(settings)
    done = fit_avatar(load_kit(settings.kit), avatar, settings.avatar.fit)
    if avatar is not None:
        print(f"livedrummer: fit: {done.line}", file=sys.stderr)
    return done.kit, done.avatar
