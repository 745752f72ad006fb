"""``livedrummer practice score|history``: judge a played take against its reference.

``practice score REF.mid TAKE.mid`` reads both files through the one front door
(:func:`~.common.read_performance`; ``--map`` for the reference, ``--take-map`` for the take,
both ``auto`` by default, so a GMD reference and a ``sessions export`` take each get the map
that knows them), judges the take with :mod:`livedrummer.practice.match` (``--window-ms``,
``--pieces``) and prints the grades of :mod:`livedrummer.practice.grade`: a few lines, or one
JSON object with ``--json``. ``--report FILE.html`` writes the self-contained HTML report
(:mod:`livedrummer.practice.report`), ``--save`` keeps the result in the practice database
(:mod:`services.practice.store`), which ``practice history`` lists and plots over days.

Each file's notices (the map ``auto`` chose, notes left out) are printed once: a reference
scored against itself, the first thing a newcomer tries, does not say them again as the take.

The take is judged on the reference's clock: a take the practice rig wrote
(:mod:`services.practice.take`) says in a marker where the reference starts in it, and that
lead is subtracted; any other file is judged as written, its time zero the reference's.
``--shift-ms`` moves the whole take (a known input offset) before judging; ``--align first``
moves it so its first hit lands on the reference's first note (a ``sessions export`` starts at
its first hit, wherever the reference started).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .files import add_channel_option, add_map_option
from .parsing import Subparsers, add_command
from .practice_setup import (
    add_db_option,
    add_judge_options,
    add_pass_options,
    judge_settings,
    pass_setup,
    summary_lines,
)


class _AnyName(dict[str, argparse.ArgumentParser]):
    """The action table, saying yes to any name (argparse checks a choice before it calls the
    action; :class:`_Actions` then reads an unknown first word as ``play``'s reference)."""

    def __contains__(self, key: object) -> bool:
        return True


class _Actions(argparse._SubParsersAction):  # type: ignore[type-arg]
    """``practice REF.mid ...`` is ``practice play REF.mid ...``: a first word that is not an
    action name is the reference of ``play``."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._name_parser_map = self.choices = _AnyName()

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser:
        self._name_parser_map = dict(self._name_parser_map)  # argparse's own name check
        try:
            parser: argparse.ArgumentParser = super().add_parser(name, **kwargs)
            return parser
        finally:
            self._name_parser_map = self.choices = _AnyName(self._name_parser_map)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        if values and not dict.__contains__(self._name_parser_map, values[0]):
            values = ["play", *values]
        super().__call__(parser, namespace, values, option_string)


def register(sub: Subparsers) -> None:
    from .practice_live import add_live_options

    p = add_command(sub, "practice", _usage, "play along with a reference, scored note by note")
    p.epilog = (
        "Play along with a reference (practice REF.mid --virtual NAME | --midi PORT | --serial "
        "DEV ...), score a recorded take (practice score REF.mid TAKE.mid), or see progress "
        "(practice history)."
    )
    actions = p.add_subparsers(dest="action", metavar="ACTION", action=_Actions)
    play = actions.add_parser(
        "play",
        help="play along with a reference (the default action: practice REF.mid ...)",
        description="Play along with a reference to a click; each pass scored.",
    )
    add_live_options(play)
    play.set_defaults(func=_run_live)
    sc = actions.add_parser(
        "score",
        help="judge a recorded take against its reference",
        description="Judge a recorded take against its reference, note by note.",
    )
    sc.add_argument("reference", type=Path, metavar="REF.mid", help="the reference (what to play)")
    sc.add_argument("take", type=Path, metavar="TAKE.mid", help="what was played")
    add_map_option(sc)
    sc.add_argument(
        "--take-map",
        default="auto",
        metavar="MAP",
        help="note map of the take (name or .toml; auto as for --map)",
    )
    add_channel_option(sc)
    add_judge_options(sc)
    add_pass_options(sc)
    sc.add_argument(
        "--shift-ms",
        type=float,
        default=0.0,
        help="add this to every take time before judging (ms)",
    )
    sc.add_argument(
        "--align",
        choices=("none", "first"),
        default="none",
        help="first: move the take so its first hit lands on the reference's first "
        "note (a sessions export starts at its first hit) (default none)",
    )
    sc.add_argument("--json", action="store_true", help="print one JSON object")
    sc.add_argument(
        "--report",
        type=Path,
        metavar="FILE.html",
        help="write a self-contained HTML report (default: none)",
    )
    sc.add_argument(
        "--save",
        action="store_true",
        help="keep the result in the practice database (practice history)",
    )
    add_db_option(sc)
    sc.set_defaults(func=run_score)
    hi = actions.add_parser(
        "history",
        help="sessions kept, and progress over days",
        description="List the practice sessions kept, and plot progress over days.",
    )
    hi.add_argument(
        "--report",
        type=Path,
        metavar="FILE.html",
        help="write an HTML report of progress over days (default: none)",
    )
    hi.add_argument("--json", action="store_true", help="print the sessions as JSON")
    add_db_option(hi)
    hi.set_defaults(func=run_history)


def _run_live(args: argparse.Namespace) -> int:
    from .practice_live import run_live

    return run_live(args)


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer practice {REF.mid,score,history} ...", file=sys.stderr)
    return 2


def _same_file(a: Path | str, b: Path | str) -> bool:
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False


def run_score(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.errors import LivedrummerError
    from livedrummer.practice.grade import summary
    from livedrummer.practice.match import match_take

    from .files import read_performance

    window_ms, pieces, level = judge_settings(args)
    ref, ref_map = read_performance(args, args.reference)
    take_args = argparse.Namespace(**{**vars(args), "map": args.take_map})
    take, take_map = read_performance(take_args, args.take, quiet=True)
    same = _same_file(args.reference, args.take)
    said = set(ref.report_lines(ref_map.ignored)) if same else set()
    for line in take.report_lines(take_map.ignored):
        if line not in said:  # the reference scored against itself: its notices once
            print(f"livedrummer: {args.take}: {line}", file=sys.stderr)
    if not ref.onsets.size:
        raise LivedrummerError(f"{args.reference}: no drum notes to judge against")
    from ..practice.take import take_lead_s

    played = take.onsets.copy()
    played["time_s"] += args.shift_ms / 1e3 - take_lead_s(args.take)
    played = played[np.argsort(played["time_s"], kind="stable")]
    from livedrummer.practice.plan import pass_notes

    seg, scale = pass_setup(args, ref)
    expected = pass_notes(ref.onsets, seg, scale)
    if args.align == "first" and played.size and expected.size:
        played["time_s"] += float(expected["time_s"][0]) - float(played["time_s"][0])
    matching = match_take(expected, played, window_ms, pieces)
    result = summary(matching, level)
    result["reference"] = str(args.reference)
    result["take"] = str(args.take)
    if args.report is not None:
        from .practice_out import write_take_report

        write_take_report(args.report, result, ref, matching, seg, scale)
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
