"""The parser's vocabulary: help that states every default, renamed options, subcommands.

One vocabulary: an option that means the same thing in several subcommands is defined once
(``--kit``, ``--map``, ``--sticking``, ...) or at least spelled the same; a former spelling
stays accepted, hidden from ``--help``, through :func:`add_renamed`, with a warning. Every
option's help states its default: :class:`Parser` appends ``(default X)`` to any help that
does not say it already, so the stated default cannot drift from the real one; an option
whose default is ``None`` says in its own words what happens without it. Imported to build
the parser, so it imports nothing heavy (no numpy).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from typing import Any

Subparsers = Any  # argparse's _SubParsersAction is private; its type is not worth importing


Command = Callable[[argparse.Namespace], int]


def help_with_default(action: argparse.Action) -> str:
    """An option's help with ``(default X)`` appended where it does not state its default.

    Flags (their default is off), positional arguments and options whose default is ``None``
    are left as written.
    """
    text = action.help or ""
    default = action.default
    if (
        "default" in text
        or default is None
        or default is argparse.SUPPRESS
        or action.nargs == 0
        or not action.option_strings
    ):
        return text
    shown = f"{default:g}" if isinstance(default, float) else str(default)
    return f"{text} (default {shown})".replace("%", "%%")


class _Formatter(argparse.HelpFormatter):
    def _get_help_string(self, action: argparse.Action) -> str:
        return help_with_default(action)


class Parser(argparse.ArgumentParser):
    """The CLI's argument parser: help states every default (see the module docstring)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)


class _Renamed(argparse.Action):
    """A former spelling of an option: warns, then acts as the option's current spelling."""

    def __init__(
        self, option_strings: Sequence[str], dest: str, *, new: argparse.Action, **kwargs: Any
    ) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.new = new

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        current = self.new.option_strings[-1]
        print(f"livedrummer: warning: {option_string} is now spelled {current}", file=sys.stderr)
        self.new(parser, namespace, values, current)


def add_renamed(parser: Any, old: str, new: argparse.Action) -> None:
    """Accept ``old``, an option's former spelling, as ``new`` (hidden from help; warns).

    ``parser``: the parser or argument group ``new`` was added to.
    """
    parser.add_argument(
        old,
        action=_Renamed,
        new=new,
        nargs=new.nargs,
        type=new.type,
        choices=new.choices,
        metavar=new.metavar,
        default=argparse.SUPPRESS,
        help=argparse.SUPPRESS,
    )


def add_command(
    sub: Subparsers, name: str, func: Command, help_: str | None = None
) -> argparse.ArgumentParser:
    """The parser of subcommand ``name``; its one-line help is the one ``COMMANDS`` gives.

    (``livedrummer --help`` lists the subcommands from that table without importing them;
    a ``help_`` given here must say the same.)
    """
    from .commands import COMMANDS

    summary = COMMANDS[name]
    if help_ is not None and help_ != summary:
        raise ValueError(f"subcommand {name}: help {help_!r} differs from COMMANDS {summary!r}")
    parser: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=summary)
    parser.set_defaults(func=func)
    return parser
