"""``livedrummer practice score|history``: judge a played take against its reference.

``practice score REF.mid TAKE.mid`` reads both files through the one front door
(:func:`~.common.read_performance`; ``--map`` for the reference, ``--take-map`` for the take,
both ``auto`` by default, so a GMD reference and a ``sessions export`` take each get the map
that knows them), judges the take with :mod:`livedrummer.practice.match` (``--window-ms``,
``--pieces``) and prints the grades of :mod:`livedrummer.practice.grade`: a few lines, or one
JSON object with ``--json``. ``--report FILE.html`` writes the self-contained HTML report
(:mod:`livedrummer.practice.report`), ``--save`` keeps the result in the practice database
(:mod:`services.practice.store`), which ``practice history`` lists and plots over days.

The take is judged on the reference's clock: a take the practice rig wrote
(:mod:`services.practice.take`) says in a marker where the reference starts in it, and that
lead is subtracted; any other file is judged as written, its time zero the reference's.
``--shift-ms`` moves the whole take (a known input offset) before judging.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .common import Subparsers, add_channel_option, add_command, add_map_option


def register(sub: Subparsers) -> None:
    p = add_command(sub, "practice", _usage, "score a take against a reference; progress reports")
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    sc = actions.add_parser("score", help="judge a recorded take against its reference",
                            description="Judge a recorded take against its reference, note "
                            "by note.")  # fmt: skip
    sc.add_argument("reference", type=Path, metavar="REF.mid", help="the reference (what to play)")
    sc.add_argument("take", type=Path, metavar="TAKE.mid", help="what was played")
    add_map_option(sc)
    sc.add_argument("--take-map", default="auto", metavar="MAP",
                    help="note map of the take (name or .toml; auto as for --map)")  # fmt: skip
    add_channel_option(sc)
    add_judge_options(sc)
    sc.add_argument("--shift-ms", type=float, default=0.0,
                    help="add this to every take time before judging (ms)")  # fmt: skip
    sc.add_argument("--json", action="store_true", help="print one JSON object")
    sc.add_argument("--report", type=Path, metavar="FILE.html",
                    help="write a self-contained HTML report (default: none)")  # fmt: skip
    sc.add_argument("--save", action="store_true",
                    help="keep the result in the practice database (practice history)")  # fmt: skip
    add_db_option(sc)
    sc.set_defaults(func=run_score)
    hi = actions.add_parser("history", help="sessions kept, and progress over days",
                            description="List the practice sessions kept, and plot progress "
                            "over days.")  # fmt: skip
    hi.add_argument("--report", type=Path, metavar="FILE.html",
                    help="write an HTML report of progress over days (default: none)")  # fmt: skip
    hi.add_argument("--json", action="store_true", help="print the sessions as JSON")
    add_db_option(hi)
    hi.set_defaults(func=run_history)


def add_judge_options(p: argparse.ArgumentParser) -> None:
    """``--window-ms``, ``--pieces``, ``--level``: how a take is judged (score and live)."""
    p.add_argument("--window-ms", type=float, default=100.0,
                   help="a note matches a hit within ± this many ms (default 100)")  # fmt: skip
    p.add_argument("--pieces", metavar="P,P",
                   help="judge only these pieces, e.g. snare,hihat (default: all)")  # fmt: skip
    p.add_argument("--level", choices=("easy", "hard"), default="easy",
                   help="on time within ±40 ms (easy) or ±20 ms (hard) (default easy)")  # fmt: skip


def add_db_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--db", type=Path, metavar="FILE",
                   help="practice database (default: $LIVEDRUMMER_HOME/practice.sqlite when "
                   "LIVEDRUMMER_HOME is set, else $XDG_DATA_HOME/livedrummer/practice.sqlite, "
                   "~/.local/share by default)")  # fmt: skip


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer practice {score,history} ...", file=sys.stderr)
    return 2


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


def run_score(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.errors import LivedrummerError
    from livedrummer.practice.grade import summary
    from livedrummer.practice.match import match_take

    from .common import read_performance

    window_ms, pieces, level = judge_settings(args)
    ref, _ = read_performance(args, args.reference)
    take_args = argparse.Namespace(**{**vars(args), "map": args.take_map})
    take, _ = read_performance(take_args, args.take)
    if not ref.onsets.size:
        raise LivedrummerError(f"{args.reference}: no drum notes to judge against")
    from ..practice.take import take_lead_s

    played = take.onsets.copy()
    played["time_s"] += args.shift_ms / 1e3 - take_lead_s(args.take)
    played = played[np.argsort(played["time_s"], kind="stable")]
    matching = match_take(ref.onsets, played, window_ms, pieces)
    result = summary(matching, level)
    result["reference"] = str(args.reference)
    result["take"] = str(args.take)
    if args.report is not None:
        from .practice_out import write_take_report

        write_take_report(args.report, result, ref, matching)
    if args.save:
        from ..practice.store import PracticeStore

        with PracticeStore.open(args.db) as store:
            result["session_id"] = store.add(result, kind="score")
    if args.json:
        print(json.dumps(result))
    else:
        for line in summary_lines(result):
            print(line)
        if args.report is not None:
            print(f"report: {args.report}")
    return 0


def summary_lines(result: dict[str, Any]) -> list[str]:
    """The take's result for a person: totals, timing, then one line per piece."""

    def timing(r: dict[str, Any]) -> str:
        if r["mean_offset_ms"] is None:
            return "no hits"
        return f"mean {r['mean_offset_ms']:+.1f} ms, sd {r['sd_offset_ms']:.1f} ms"

    lines = [
        f"{result['reference_notes']} notes: {result['hits']} hits, "
        f"{result['wrong_piece']} wrong piece, {result['missed']} missed, {result['extra']} extra",
        f"timing: {timing(result)}; perfect {result['perfect']}, good {result['good']}, "
        f"ok {result['ok']}",
        f"accuracy {result['accuracy_pct']:.1f} % (±{result['level_window_ms']:g} ms), "
        f"score {result['score']:.1f}/100",
    ]
    for piece, r in result["per_piece"].items():
        lines.append(
            f"  {piece:<12} {r['hits']:>4}/{r['reference_notes']:<4} hits  "
            f"{r['missed']:>3} missed  {r['wrong_piece']:>3} wrong  {r['extra']:>3} extra  "
            f"{timing(r)}"
        )
    return lines


def run_history(args: argparse.Namespace) -> int:
    from ..practice.store import PracticeStore

    with PracticeStore.open(args.db) as store:
        sessions = store.sessions()
        where = store.path
    if args.json:
        print(json.dumps({"db": str(where), "sessions": sessions}))
    elif not sessions:
        print(f"no practice sessions in {where}")
    else:
        for s in sessions:
            print(
                f"{s['id']:>4}  {s['started']}  {s['kind']:<5}  {Path(s['reference']).name}  "
                f"{s['hits']}/{s['reference_notes']} hits  accuracy {s['accuracy_pct']:.1f} %  "
                f"score {s['score']:.1f}"
            )
    if args.report is not None:
        from .practice_out import write_history_report

        write_history_report(args.report, sessions)
        if not args.json:
            print(f"report: {args.report}")
    return 0
