"""What the ``practice`` commands share: the options of judging and passes, the session
database option, the settings they resolve and the summary lines of a take.

Its own module so that ``practice`` (the file commands) and ``practice_live`` (the live
take) both use it without importing each other.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def add_judge_options(p: argparse.ArgumentParser) -> None:
    """``--window-ms``, ``--pieces``, ``--level``: how a take is judged (score and live)."""
    p.add_argument(
        "--window-ms",
        type=float,
        default=100.0,
        help="a note matches a hit within ± this many ms (default 100)",
    )
    p.add_argument(
        "--pieces", metavar="P,P", help="judge only these pieces, e.g. snare,hihat (default: all)"
    )
    p.add_argument(
        "--level",
        choices=("easy", "hard"),
        default="easy",
        help="on time within ±40 ms (easy) or ±20 ms (hard) (default easy)",
    )


def add_pass_options(p: argparse.ArgumentParser) -> None:
    """``--tempo``, ``--bpm``, ``--bars``: the pass judged (score) or played (live)."""
    speed = p.add_mutually_exclusive_group()
    speed.add_argument(
        "--tempo",
        type=float,
        metavar="SCALE",
        help="play the reference at this speed, e.g. 0.8 (default 1)",
    )
    speed.add_argument(
        "--bpm", type=float, help="play the reference at this tempo (default: its own)"
    )
    p.add_argument(
        "--bars", metavar="BAR:BAR", help="loop bars A to B of the reference, from 1 (default: all)"
    )


def pass_setup(args: argparse.Namespace, reference: Any) -> tuple[Any, float]:
    """(segment, tempo scale) that ``--bars``, ``--tempo`` and ``--bpm`` ask for."""
    from livedrummer.errors import ConfigError
    from livedrummer.practice.plan import first_bpm, parse_loop, segment

    try:
        loop = None if args.bars is None else parse_loop(args.bars)
        seg = segment(reference.grid, reference.duration_s, loop)
    except ValueError as exc:
        raise ConfigError(f"--bars: {exc}") from None
    scale = 1.0
    if args.tempo is not None:
        if not 0.1 <= args.tempo <= 4.0:
            raise ConfigError(f"--tempo {args.tempo:g}: expected 0.1..4")
        scale = args.tempo
    elif args.bpm is not None:
        if not 20 <= args.bpm <= 400:
            raise ConfigError(f"--bpm {args.bpm:g}: expected 20..400")
        scale = args.bpm / first_bpm(reference.grid, seg)
    return seg, scale


def add_db_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--db",
        type=Path,
        metavar="FILE",
        help="practice database (default: $LIVEDRUMMER_HOME/practice.sqlite when "
        "LIVEDRUMMER_HOME is set, else $XDG_DATA_HOME/livedrummer/practice.sqlite, "
        "~/.local/share by default)",
    )


def judge_settings(args: argparse.Namespace) -> tuple[float, frozenset[int] | None, Any]:
    """(window ms, piece codes or None, Level) from the options; one line when wrong."""
    from livedrummer.errors import ConfigError
    from livedrummer.practice.grade import Level
    from livedrummer.practice.match import parse_pieces

    if not 0 < args.window_ms <= 1000:
        raise ConfigError(f"--window-ms {args.window_ms:g}: expected > 0 and <= 1000")
    pieces = None
    if args.pieces is not None:
        try:
            pieces = parse_pieces(args.pieces)
        except ValueError as exc:
            raise ConfigError(f"--pieces: {exc}") from None
    return args.window_ms, pieces, Level(args.level)


def summary_lines(result: dict[str, Any]) -> list[str]:
    """The take's result for a person: totals, timing, then one line per piece."""

    def timing(r: dict[str, Any]) -> str:
        if r["mean_offset_ms"] is None:
            return "no hits"
        return f"mean {r['mean_offset_ms']:+.1f} ms, sd {r['sd_offset_ms']:.1f} ms"

    from livedrummer.practice.grade import window_words

    w = window_words(result)
    lines = [
        f"{result['reference_notes']} notes: {result['hits']} hits ({w['hits']}), "
        f"{result['wrong_piece']} wrong piece, {result['missed']} missed, {result['extra']} extra",
        f"timing: {timing(result)}; perfect {result['perfect']} ({w['perfect']}), "
        f"good {result['good']} ({w['good']}), ok {result['ok']} ({w['ok']})",
        f"accuracy {result['accuracy_pct']:.1f} % ({w['on_time']}), "
        f"score {result['score']:.1f}/100",
    ]
    for piece, r in result["per_piece"].items():
        lines.append(
            f"  {piece:<12} {r['hits']:>4}/{r['reference_notes']:<4} hits  "
            f"{r['missed']:>3} missed  {r['wrong_piece']:>3} wrong  {r['extra']:>3} extra  "
            f"{timing(r)}"
        )
    return lines
