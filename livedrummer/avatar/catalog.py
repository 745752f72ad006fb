"""Which avatars a NAME can pick: the built-in character, bundled files, the user's files.

Kept apart from the loader (:mod:`livedrummer.avatar.loader`) so that listing avatars
(``livedrummer kits``, ``livedrummer avatars``) reads folder listings only: no glTF parsing,
no numpy, so those commands answer at once. Bundled avatars live in ``kits/avatars/``, the
user's in ``$LIVEDRUMMER_HOME/avatars/``; a user's file wins over a bundled one of the same
name. Limits: a file is listed by its name and suffix; whether it loads is the loader's to say.
"""

from __future__ import annotations

from pathlib import Path

from livedrummer.resources import data_dir, user_home

SUFFIXES = (".vrm", ".glb", ".gltf")
DEFAULT = "default"


def avatar_dirs() -> list[tuple[str, Path]]:
    """(kind, folder) searched for avatar names, bundled first (later folders win)."""
    return [("bundled", data_dir("kits") / "avatars"), ("user", user_home() / "avatars")]


def list_avatars() -> list[tuple[str, str, str]]:
    """(name, kind, path) of every avatar a NAME can pick, the built-in character first."""
    found: dict[str, tuple[str, str, str]] = {DEFAULT: (DEFAULT, "built-in", "")}
    for kind, folder in avatar_dirs():
        if not folder.is_dir():
            continue
        for path in sorted(folder.iterdir()):
            if path.suffix.lower() in SUFFIXES and path.is_file():
                found[path.stem] = (path.stem, kind, str(path))
    return list(found.values())
