"""The ``livedrummer`` command: one entry point, one module per subcommand.

The CLI is an I/O edge: it parses arguments, calls the library, prints, and turns every
:class:`~livedrummer.errors.LivedrummerError` into one line on stderr and exit status 2 (no
traceback: a show technician needs the file and the problem, not a stack). Each subcommand is a
module in this package with ``register(subparsers)``. Start-up is lazy, so that ``livedrummer
--help`` and ``livedrummer kits`` answer at once (no numpy, no sockets, no GPU): :data:`COMMANDS`
holds every subcommand's one-line help, ``--help`` is built from it alone, and a command line
imports only the module of the subcommand it names; that module's heavy imports (numpy, audio,
GPU, sockets) happen inside its command function. Adding a subcommand is adding a module and
its line to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from livedrummer import __version__
from livedrummer.errors import LivedrummerError

from .commands import COMMANDS

EXIT_USAGE = 2


def command_named(argv: Sequence[str]) -> str | None:
    """The subcommand a command line names: its first word that is not an option."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; given ``argv``, only the subcommand it names is built (see above)."""
    from .parsing import Parser

    parser = Parser(
        prog="livedrummer",
        description="Turn an electronic drum kit or a MIDI file into a 3D virtual drummer.",
    )
    parser.add_argument("--version", action="version", version=f"livedrummer {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log more detail")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = None if argv is None else command_named(argv)
    for name, summary in COMMANDS.items():
        if argv is None or name == wanted:
            importlib.import_module(f".{name}", __package__).register(sub)
        elif wanted is None:  # the list for --help or for an error: no other module needed
            sub.add_parser(name, help=summary, description=summary)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    words = sys.argv[1:] if argv is None else list(argv)
    args = build_parser(words).parse_args(words)
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
