"""Finding named configuration files (kits, note maps) along the search path.

A *spec* on the command line is either a path to a ``.toml`` file or a name. Names are looked
up as ``<name>.toml`` in :func:`livedrummer.resources.search_dirs`; later folders override
earlier ones. Kits additionally accept ``<name>-left`` / ``<name>-right``: the named kit
mirrored for the other hand (see :meth:`livedrummer.kit.model.Kit.mirrored`), so no mirrored copy of
any file ever exists.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from livedrummer.resources import search_dirs


@dataclass(frozen=True, slots=True)
class Entry:
    """A named file found on the search path."""

    name: str
    path: Path


def entries(sub: str) -> dict[str, Entry]:
    """Every ``*.toml`` under the search folders for ``sub``, by name (stem)."""
    found: dict[str, Entry] = {}
    for folder in search_dirs(sub):
        if folder.is_dir():
            for path in sorted(folder.glob("*.toml")):
                found[path.stem] = Entry(path.stem, path)
    return found


def looks_like_path(spec: str) -> bool:
    return spec.endswith(".toml") or "/" in spec or "\\" in spec or Path(spec).is_file()
