"""``livedrummer kits``: every kit, extension, note map, preset and avatar a name can pick, with
any file's error (listing reads no avatar file: see :mod:`livedrummer.avatar.catalog`)."""

from __future__ import annotations

import argparse

from livedrummer.avatar.catalog import list_avatars
from livedrummer.body.expression import load_expression
from livedrummer.errors import LivedrummerError
from livedrummer.kit.catalog import entries
from livedrummer.kit.loader import load_extension, load_kit_file
from livedrummer.midi.notemap import load_note_map_file

from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    add_command(sub, "kits", run, "list kits, note maps, presets and avatars")


def run(args: argparse.Namespace) -> int:
    print("kits:")
    for name, entry in sorted(entries("kits").items()):
        try:
            kit = load_kit_file(entry.path)
        except LivedrummerError as exc:
            print(f"  {name:<16} ERROR {exc}")
            continue
        mirror = f"{name}-{'left' if kit.handedness == 'right' else 'right'}"
        print(f"  {name:<16} {kit.description} [{entry.path}]")
        print(f"  {mirror:<16} {name} mirrored for a {mirror.rsplit('-', 1)[1]}-handed drummer")
    print("kit extensions (KIT+NAME adds their pieces to any kit):")
    for name, entry in sorted(entries("kits/extensions").items()):
        try:
            _, pieces = load_extension(name)
        except LivedrummerError as exc:
            print(f"  {name:<16} ERROR {exc}")
            continue
        print(f"  {'+' + name:<16} {', '.join(p.name for p in pieces)} [{entry.path}]")
    print("note maps (auto: the one that knows the most of a file's notes):")
    for name, entry in sorted(entries("kits/maps").items()):
        try:
            nm = load_note_map_file(entry.path)
        except LivedrummerError as exc:
            print(f"  {name:<16} ERROR {exc}")
            continue
        print(f"  {name:<16} {nm.description} ({len(nm.notes)} notes) [{entry.path}]")
        for source in nm.sources:
            print(f"  {'':<16}   source: {source}")
    print("expression presets (--preset NAME):")
    for name, entry in sorted(entries("kits/presets").items()):
        try:
            load_expression(str(entry.path))
        except LivedrummerError as exc:
            print(f"  {name:<16} ERROR {exc}")
            continue
        print(f"  {name:<16} [{entry.path}]")
    print("avatars (--avatar NAME; livedrummer avatar info NAME):")
    for name, kind, path in list_avatars():
        print(f"  {name:<16} {kind:<8} [{path or 'drawn from the body proportions'}]")
    return 0
