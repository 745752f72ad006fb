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

from .common import Subparsers, add_channel_option, add_command, add_map_option


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
    play = actions.add_parser("play", help="play along with a reference (the default action: "
                              "practice REF.mid ...)", description="Play along with a reference "
                              "to a click; each pass scored.")  # fmt: skip
    add_live_options(play)
    play.set_defaults(func=_run_live)
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
    add_pass_options(sc)
    sc.add_argument("--shift-ms", type=float, default=0.0,
                    help="add this to every take time before judging (ms)")  # fmt: skip
    sc.add_argument("--align", choices=("none", "first"), default="none",
                    help="first: move the take so its first hit lands on the reference's first "
                    "note (a sessions export starts at its first hit) (default none)")  # fmt: skip
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


def add_pass_options(p: argparse.ArgumentParser) -> None:
    """``--tempo``, ``--bpm``, ``--bars``: the pass judged (score) or played (live)."""
    speed = p.add_mutually_exclusive_group()
    speed.add_argument("--tempo", type=float, metavar="SCALE",
                       help="play the reference at this speed, e.g. 0.8 (default 1)")  # fmt: skip
    speed.add_argument("--bpm", type=float,
                       help="play the reference at this tempo (default: its own)")  # fmt: skip
    p.add_argument("--bars", metavar="BAR:BAR",
                   help="loop bars A to B of the reference, from 1 (default: all)")  # fmt: skip


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


def _run_live(args: argparse.Namespace) -> int:
    from .practice_live import run_live

    return run_live(args)


def add_db_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--db", type=Path, metavar="FILE",
                   help="practice database (default: $LIVEDRUMMER_HOME/practice.sqlite when "
                   "LIVEDRUMMER_HOME is set, else $XDG_DATA_HOME/livedrummer/practice.sqlite, "
                   "~/.local/share by default)")  # fmt: skip


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer practice {REF.mid,score,history} ...", file=sys.stderr)
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

    from .common import read_performance

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
