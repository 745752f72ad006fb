"""Show control on the command line: ``--osc``, ``--osc-allow`` and ``--cues`` (see
:mod:`services.show.osc` and :mod:`livedrummer.live.cues`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def add_osc_options(p: argparse.ArgumentParser, what: str) -> None:
    """``--osc PORT`` and ``--osc-allow ADDR,...`` (see :mod:`services.show.osc`)."""
    p.add_argument(
        "--osc",
        type=int,
        metavar="PORT",
        help=f"OSC show control on this UDP port ({what}; no authentication: "
        "loopback only unless --osc-allow) (default: none)",
    )
    p.add_argument(
        "--osc-allow",
        metavar="ADDR,...",
        help="also take OSC from these sender addresses (default: loopback only)",
    )
    p.add_argument(
        "--cues",
        type=Path,
        metavar="FILE",
        help="cue list (TOML): OSC /livedrummer/cue NAME fires a cue, and live "
        "its bar cues fire as the beat tracker counts bars (default: none)",
    )


def cues_of(args: argparse.Namespace) -> dict[str, Any]:
    """``--cues FILE`` loaded (one line naming the file, cue and key when it is bad)."""
    if getattr(args, "cues", None) is None:
        return {}
    from livedrummer.live.cues import load_cues

    return dict(load_cues(args.cues))


def osc_allow(args: argparse.Namespace) -> tuple[str, ...]:
    """``--osc-allow`` checked: one line naming a bad address."""
    from livedrummer.errors import ConfigError

    from ..show.osc import parse_allow

    if args.osc is not None and not 0 <= args.osc <= 65535:
        raise ConfigError(f"--osc: expected a UDP port 0..65535 (got {args.osc})")
    try:
        return parse_allow(args.osc_allow)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
