"""``livedrummer avatars``: the avatars ``--avatar NAME`` can pick.

The built-in character (``default``), then the ``.vrm``/``.glb``/``.gltf`` files bundled in
``kits/avatars/`` and those in the user's folder (``~/.config/livedrummer/avatars/``, or
``$LIVEDRUMMER_HOME/avatars``), each with where it is. Files are listed, not read: ``livedrummer
avatar info NAME`` reads one.
"""

from __future__ import annotations

import argparse
import json

from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "avatars", run)
    p.add_argument("--json", action="store_true", help="print one JSON list")


def run(args: argparse.Namespace) -> int:
    from livedrummer.avatar.catalog import avatar_dirs, list_avatars

    found = list_avatars()
    if args.json:
        print(json.dumps([{"name": n, "kind": k, "path": p or None} for n, k, p in found]))
        return 0
    width = max(len(n) for n, _, _ in found)
    for name, kind, path in found:
        print(f"{name:<{width}}  {kind:<8}  {path or 'drawn from the body proportions'}")
    print("folders: " + ", ".join(f"{kind} {folder}" for kind, folder in avatar_dirs()))
    return 0
