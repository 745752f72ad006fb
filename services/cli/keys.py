"""``livedrummer keys``: make and list CURVE key pairs for remote jams and remote displays.

``keys new NAME`` writes ``NAME.key_secret`` (our key pair, mode 0600: never share it) and
``NAME.key`` (the public key: give it to the other site, which puts it in its ``--allow``
folder) into ``$LIVEDRUMMER_HOME/keys`` or ``--keys-dir``; it never overwrites a key. ``keys
list`` shows the public keys in that folder. The file format is described in
:mod:`livedrummer.protocol.keys`.

This module also holds the CURVE options the network commands share (``--curve-secret``,
``--server-key``, ``--allow``, ``--insecure``) and their translation into a
:class:`services.wire.net.Security`, so ``input``, ``synth`` and ``display --live`` spell and
check them the same way.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING

from livedrummer.errors import KeyFileError, LivedrummerError
from livedrummer.protocol.keys import (
    PUBLIC_SUFFIX,
    SECRET_SUFFIX,
    check_name,
    format_key_file,
    read_key_file,
)
from livedrummer.resources import user_home

from .parsing import Subparsers, add_command, add_renamed

if TYPE_CHECKING:
    from ..wire.net import Security


def register(sub: Subparsers) -> None:
    p = add_command(sub, "keys", _usage)
    actions = p.add_subparsers(dest="keys_command", metavar="ACTION", required=True)
    new = actions.add_parser("new", help="write NAME.key_secret and NAME.key")
    new.add_argument("name", help="key name (letters, digits, _ . -)")
    new.set_defaults(func=run_new)
    lst = actions.add_parser("list", help="list the public keys in the key folder")
    lst.set_defaults(func=run_list)
    for action in (new, lst):  # --dir: its former spelling
        add_renamed(
            action,
            "--dir",
            action.add_argument(
                "--keys-dir",
                type=Path,
                metavar="DIR",
                help="key folder (default $LIVEDRUMMER_HOME/keys)",
            ),
        )


def _usage(args: argparse.Namespace) -> int:  # unreachable: ACTION is required
    raise KeyFileError("keys: give an action: 'keys new NAME' or 'keys list'")


def key_dir(given: Path | None) -> Path:
    return given if given is not None else user_home() / "keys"


def run_new(args: argparse.Namespace) -> int:
    import zmq

    name = check_name(args.name)
    folder = key_dir(args.keys_dir)
    public_path = folder / f"{name}{PUBLIC_SUFFIX}"
    secret_path = folder / f"{name}{SECRET_SUFFIX}"
    for path in (public_path, secret_path):
        if path.exists():
            raise KeyFileError(f"{path}: already exists (keys are never overwritten)")
    public, secret = zmq.curve_keypair()
    try:
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        _write(secret_path, format_key_file(name, public, secret), 0o600)
        _write(public_path, format_key_file(name, public), 0o644)
    except OSError as exc:
        raise KeyFileError(f"{folder}: cannot write keys: {exc.strerror or exc}") from None
    print(f"secret (keep private): {secret_path}")
    print(f"public (share):        {public_path}")
    print(f"public key: {public.decode()}")
    return 0


def _write(path: Path, text: str, mode: int) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "w", encoding="ascii") as f:
        f.write(text)
    os.chmod(path, mode)  # the umask may have narrowed or the file system widened it


def run_list(args: argparse.Namespace) -> int:
    folder = key_dir(args.keys_dir)
    files = sorted(folder.glob(f"*{PUBLIC_SUFFIX}")) if folder.is_dir() else []
    if not files:
        print(f"no keys in {folder} (make one with 'livedrummer keys new NAME')")
        return 0
    for path in files:
        name = path.name[: -len(PUBLIC_SUFFIX)]
        try:
            pair = read_key_file(path, secret=False)
        except LivedrummerError as exc:
            print(f"  {name:<20} ERROR {exc}")
            continue
        own = " (+ secret)" if (folder / f"{name}{SECRET_SUFFIX}").exists() else ""
        print(f"  {name:<20} {pair.public.decode()}{own}")
    return 0


def add_curve_options(parser: argparse.ArgumentParser, *, server: bool, client: bool) -> None:
    """Add the CURVE options: ``server`` for commands that bind, ``client`` for connecting."""
    g = parser.add_argument_group("security (CURVE; see 'livedrummer keys')")
    g.add_argument(
        "--curve-secret",
        type=Path,
        metavar="FILE",
        help="our NAME.key_secret: encrypt and authenticate remote streams "
        "(default: none, plain text)",
    )
    if client:
        g.add_argument(
            "--server-key",
            type=Path,
            metavar="FILE",
            help="the public .key of the service we connect to (default: none, plain text)",
        )
    if server:
        g.add_argument(
            "--allow",
            type=Path,
            metavar="DIR",
            help="only clients with a public .key file in DIR may connect (default: any client)",
        )
        g.add_argument(
            "--insecure",
            action="store_true",
            help="allow binding a non-loopback address without CURVE",
        )


def security_from_args(args: argparse.Namespace) -> Security:
    """The :class:`services.wire.net.Security` the parsed CURVE options describe."""
    from ..wire.net import Security

    return Security.from_files(
        secret=args.curve_secret,
        server_key=getattr(args, "server_key", None),
        allow=getattr(args, "allow", None),
        insecure=getattr(args, "insecure", False),
    )
