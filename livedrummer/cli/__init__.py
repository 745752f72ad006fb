"""The ``livedrummer`` command: one entry point, one module per subcommand.

The CLI is an I/O edge: it parses arguments, calls the library, prints, and turns every
:class:`~livedrummer.errors.LivedrummerError` into one line on stderr and exit status 2 (no
traceback: a show technician needs the file and the problem, not a stack). Each subcommand is a
module in this package with ``register(subparsers)``; its heavy imports (audio, GPU, sockets)
happen inside the command function, so ``inspect`` stays fast and works where those libraries
cannot load. Adding a subcommand is adding a module and its name to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from livedrummer import __version__
from livedrummer.errors import LivedrummerError

EXIT_USAGE = 2

#: Subcommand modules of this package, in the order ``--help`` lists them.
COMMANDS: tuple[str, ...] = (
    "demo",
    "inspect",
    "kits",
    "sticking",
    "bench",
    "input",
    "ports",
    "sessions",
    "check",
    "export",
    "render",
    "display",
    "synth",
    "up",
    "keys",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="livedrummer",
        description="Turn an electronic drum kit or a MIDI file into a 3D virtual drummer.",
    )
    parser.add_argument("--version", action="version", version=f"livedrummer {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log more detail")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"livedrummer.cli.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING,
        format="livedrummer: %(levelname)s: %(message)s",
    )
    try:
        code: int = args.func(args)
    except LivedrummerError as exc:
        print(f"livedrummer: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
