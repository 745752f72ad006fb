"""Where the project's data files live: ``kits/`` (kits and ``maps/``) and ``shaders/``.

In a source checkout (and an editable install) they are the top-level folders of the
repository; a wheel carries them inside the package as ``livedrummer/_data/<name>``. Code asks
:func:`data_dir` and never builds these paths itself. User additions live in
``$LIVEDRUMMER_HOME`` (default ``~/.config/livedrummer``) and in the folders listed in
``$LIVEDRUMMER_PATH`` (``os.pathsep``-separated), each holding ``kits/`` and ``kits/maps/``.
"""

from __future__ import annotations

import os
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def data_dir(name: str) -> Path:
    """The bundled folder ``name`` (``kits`` or ``shaders``)."""
    bundled = _PACKAGE / "_data" / name
    if bundled.is_dir():
        return bundled
    return _PACKAGE.parent / name


def user_home() -> Path:
    """The per-user folder for added kits, maps, presets and calibration."""
    env = os.environ.get("LIVEDRUMMER_HOME")
    return Path(env) if env else Path.home() / ".config" / "livedrummer"


def search_dirs(sub: str) -> list[Path]:
    """Folders searched for ``sub`` (e.g. ``kits`` or ``kits/maps``), bundled first.

    Later folders win when two hold a file of the same name, so a user can override a
    bundled kit without editing the installation.
    """
    dirs = [data_dir("kits").parent / sub if sub.startswith("kits") else data_dir(sub)]
    dirs.append(user_home() / sub)
    for entry in os.environ.get("LIVEDRUMMER_PATH", "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry) / sub)
    return dirs
