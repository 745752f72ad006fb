"""``livedrummer check FILE.mid...``: is the drummer's motion physically true?

Animates each file on the kit and measures contact error at every onset, the deepest stick-tip
penetration and joint-limit violations (see :mod:`livedrummer.body.check`). Several files or
folders are checked one by one and summarised together (max over files; p99 and mean over all
onsets), with the number of strokes too fast for one hand or made with the arms crossed
(:mod:`livedrummer.sticking.metrics`). Limbs come from
:func:`livedrummer.sticking.stick_performance` (``--sticking``, and ``--score`` for one file),
as for ``livedrummer sticking``.

``--json`` prints the summary and, per file, every note as the animation played it: time,
note, piece, limb, whether it is too fast for one hand or made with the arms crossed (and how,
in ``hard``), and its contact error, so a program can hold the animation against the sticking
sheet note by note. That list grows with the notes (about 200 bytes each); ``--summary`` leaves
it out, e.g. for the whole Groove MIDI Dataset.

A folder is searched for ``.mid .midi .kar .rmi`` files in any case. A file that cannot be read
is reported on its own line and the others are checked; a file with no drum notes is reported
and left out. The count of unreadable files ends the report, and any makes the exit status 2.
A figure is only given of what was measured: with no note checked the contact error is
``null`` in ``--json`` (not 0 mm, "100 % within 5 mm"), with no file checked the penetration
and joint-limit figures are too, and ``unreadable`` lists each file that failed with its error.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.errors import LivedrummerError

from .files import add_channel_option, add_map_option, midi_files, read_performance
from .parsing import Subparsers, add_command
from .performer import add_kit_option, add_motion_options, sticking_of

if TYPE_CHECKING:
    import numpy as np

    from livedrummer.kit.model import Kit
    from livedrummer.sticking.result import Sticking


def register(sub: Subparsers) -> None:
    p = add_command(sub, "check", run)
    p.add_argument("files", nargs="*", help="Standard MIDI File(s) or folders of them")
    p.add_argument(
        "--stage",
        type=Path,
        metavar="TOML",
        help="check each drummer of a stage file on its own kit (default: none)",
    )
    add_kit_option(p)
    add_map_option(p)
    add_channel_option(p)
    add_motion_options(p)
    from .performer import add_avatar_option

    add_avatar_option(p)
    p.add_argument("--fps", type=float, default=200.0, help="frames per second checked")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--summary", action="store_true", help="--json: without the notes of each file")


def run(args: argparse.Namespace) -> int:
    if args.stage is not None:
        if args.files:
            raise LivedrummerError("check: give MIDI files or --stage, not both")
        return run_stage(args)
    if not args.files:
        raise LivedrummerError("check: give MIDI files or folders, or --stage FILE")
    import numpy as np

    from livedrummer.body.check import check
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.kit.loader import kit_that_plays, load_kit
    from livedrummer.sticking.metrics import crossings, too_fast

    kit = load_kit(args.kit)
    from .performer import avatar_of, fitting_of, rig_for

    fitting = fitting_of(args, kit, avatar_of(args))
    kit, avatar = fitting.kit, fitting.avatar
    rig = rig_for(kit, avatar)
    map_names: set[str] = set()
    expression = load_expression(args.preset) if args.preset else None
    strokes = StrokeParams(model=args.strokes)
    files = midi_files(args.files)
    if args.score is not None and len(files) != 1:
        raise LivedrummerError(
            f"--score {args.score}: a score is of one MIDI file, not of {len(files)}"
        )
    errors: list[np.ndarray] = []
    worst: dict[str, Any] = {"penetration_mm": 0.0, "file": None, "at_s": 0.0}
    totals = {"notes": 0, "not_played": 0, "joint_limit_violations": 0, "frames": 0}
    by_limit: dict[str, int] = {}
    worst_contact: tuple[float, str] = (0.0, "")
    per_file: list[dict[str, Any]] = []
    hard = {"too_fast": 0, "crossed": 0}
    no_piece: Counter[str] = Counter()  # notes of instruments the kit has no piece for
    failed: list[dict[str, str]] = []
    no_drums = 0
    for path in files:
        try:
            performance, note_map = read_performance(args, path)
        except LivedrummerError as exc:  # one line per file; the others are still checked
            print(f"livedrummer: error: {exc}", file=sys.stderr)
            failed.append({"file": str(path), "error": str(exc)})
            continue
        if not performance.onsets.size:  # said on stderr
            no_drums += 1
            continue
        map_names.add(note_map.name)
        done = perform(
            performance,
            rig,
            note_map,
            expression,
            strokes,
            sticking=sticking_of(args, performance, kit),
        )
        r = check(done.animation, done.sticking, args.fps)
        errors.append(r.contact_error_m)
        if args.json and not args.summary:
            notes = notes_json(done.sticking, kit, r.contact_error_m)
            per_file.append({"file": str(path), "sticking": done.sticking.strategy, "notes": notes})
        for key in totals:
            totals[key] += getattr(r, key)
        no_piece.update(without_piece(done.sticking))
        hard["too_fast"] += int(too_fast(done.sticking, kit).sum())
        hard["crossed"] += int(crossings(done.sticking, kit).sum())
        for k, v in r.violations_by_limit.items():
            by_limit[k] = by_limit.get(k, 0) + v
        if r.penetration_m * 1000 > worst["penetration_mm"]:
            worst = {
                "penetration_mm": r.penetration_m * 1000,
                "file": str(path),
                "at_s": r.penetration_at_s,
            }
        if r.contact_error_m.size and r.contact_error_m.max() > worst_contact[0]:
            worst_contact = (float(r.contact_error_m.max()), str(path))
    e = np.concatenate(errors) * 1000.0 if errors else np.zeros(0)
    unreadable = len(failed)
    checked = len(files) - unreadable - no_drums
    summary: dict[str, Any] = {
        "files": checked,
        "unreadable_files": unreadable,
        "files_without_drums": no_drums,
        "kit": kit.name,
        "avatar": "default" if avatar is None else avatar.source,
        **({} if avatar is None else {"fit": fitting.as_json()}),
        "map": ", ".join(sorted(map_names)) or None,
        **totals,
        **hard,
        "contact_error_mm": contact_json(e, worst_contact[1]),
        "penetration_mm": round(worst["penetration_mm"], 4) if checked else None,
        "penetration_file": worst["file"],
        "penetration_at_s": round(worst["at_s"], 4) if checked else None,
        "violations_by_limit": by_limit,
        "no_piece": dict(no_piece.most_common()),
        "kit_that_plays_them": kit_that_plays(kit, no_piece) if no_piece else None,
    }
    if not checked:
        summary["joint_limit_violations"] = None
    if failed:
        summary["unreadable"] = failed
    if args.json:
        if per_file:
            summary["per_file"] = per_file
        print(json.dumps(summary, indent=1))
    elif not checked:
        print(f"0 file(s) checked, kit {kit.name}: no figures")
    else:
        c = summary["contact_error_mm"] or {"max": 0.0, "p99": 0.0, "mean": 0.0, "within_5mm": 0.0}
        print(f"{summary['files']} file(s), kit {kit.name}, map {summary['map']}")
        print(
            f"  notes checked      {summary['notes']}  (not played: {summary['not_played']}"
            f"{no_piece_words(no_piece, kit.name, summary['kit_that_plays_them'])})"
        )
        print(
            f"  too hard to play   {hard['too_fast']} too fast for one hand, "
            f"{hard['crossed']} with the arms crossed"
        )
        if summary["contact_error_mm"] is None:
            print("  contact error mm   none (no note played)")
        else:
            print(
                f"  contact error mm   max {c['max']:.4f}  p99 {c['p99']:.4f}  "
                f"mean {c['mean']:.4f}  within 5 mm {c['within_5mm'] * 100:.3f} %"
            )
        print(
            f"  penetration mm     {summary['penetration_mm']:.3f}"
            + (f"  ({worst['file']} at {worst['at_s']:.3f} s)" if worst["file"] else "")
        )
        print(
            f"  joint-limit hits   {summary['joint_limit_violations']} of "
            f"{summary['frames']} frames  {by_limit}"
        )
    if no_drums:
        print(f"livedrummer: {no_drums} of {len(files)} files have no drum notes", file=sys.stderr)
    if unreadable:
        print(
            f"livedrummer: error: {unreadable} of {len(files)} files could not be read",
            file=sys.stderr,
        )
        return 2
    return 0


def without_piece(sticking: Sticking) -> Counter[str]:
    """Notes per instrument that the sticking's kit has no piece for."""
    from livedrummer.kit.vocabulary import INSTRUMENTS

    codes = sticking.onsets["instrument"][sticking.piece < 0]
    return Counter(INSTRUMENTS[int(c)] for c in codes.tolist())


def no_piece_words(no_piece: Counter[str], kit: str, plays: str | None) -> str:
    """``; tambourine x2, cowbell x2 have no piece on rock5: --kit rock5+percussion plays
    them`` (empty when the kit has a piece for every note)."""
    if not no_piece:
        return ""
    listed = ", ".join(f"{name} x{n}" for name, n in no_piece.most_common())
    then = f": --kit {plays} plays them" if plays else ""
    return f"; {listed} have no piece on {kit}{then}"


def contact_json(error_mm: np.ndarray, worst_file: str) -> dict[str, Any] | None:
    """The contact error's figures over every played note, ``None`` when none was played."""
    from livedrummer.body.check import contact_figures

    figures = contact_figures(error_mm)
    return None if figures is None else {**figures, "worst_file": worst_file or None}


def notes_json(sticking: Sticking, kit: Kit, contact_error_m: np.ndarray) -> list[dict[str, Any]]:
    """Every note as animated: what ``sticking --json`` says of it, and its contact error
    (``None`` for a note no limb plays)."""
    from .sticking import as_json

    rows = as_json(sticking, kit)
    played = (sticking.limb >= 0) & (sticking.piece >= 0)
    error_mm = iter((contact_error_m * 1000.0).tolist())
    for row, is_played in zip(rows, played.tolist(), strict=True):
        row["contact_error_mm"] = round(next(error_mm), 4) if is_played else None
    return rows


def run_stage(args: argparse.Namespace) -> int:
    """``check --stage``: each drummer's part animated on its own kit, checked alone."""
    from livedrummer.body.check import check
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import perform
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.kit.loader import load_kit
    from livedrummer.stage.stagefile import load_stage

    from .performer import rig_for
    from .staging import stage_parts

    stage = load_stage(args.stage)
    drummers: list[dict[str, Any]] = []
    for part in stage_parts(stage, args):
        p = part.performer
        kit = load_kit(p.kit)
        avatar = None
        if p.avatar is not None:
            from .performer import avatar_of, fitted

            avatar = avatar_of(argparse.Namespace(avatar=p.avatar))
            kit, avatar = fitted(args, kit, avatar)
        expression = load_expression(p.preset) if p.preset else None
        sticking = sticking_of(args, part.performance, kit)
        done = perform(
            part.performance,
            rig_for(kit, avatar),
            part.note_map,
            expression,
            StrokeParams(model=args.strokes),
            sticking=sticking,
        )
        r = check(done.animation, done.sticking, args.fps)
        e = r.contact_error_m * 1000.0
        drummers.append({
            "id": part.label, "kit": kit.name, "channel": p.channel,
            "at": [round(part.placement.x, 3), round(part.placement.y, 3)],
            "yaw_deg": round(part.placement.yaw_deg, 2),
            "notes": int(part.performance.onsets.size), "played": int(e.size),
            "contact_error_mm_max": round(float(e.max()), 4) if e.size else 0.0,
            "penetration_mm": round(r.penetration_m * 1000.0, 4),
            "joint_limit_violations": r.joint_limit_violations,
        })  # fmt: skip
    if args.json:
        print(json.dumps({"stage": str(args.stage), "drummers": drummers}, indent=1))
    else:
        print(f"stage {args.stage}: {len(drummers)} drummers")
        for d in drummers:
            print(
                f"  {d['id']:<12} kit {d['kit']:<12} at ({d['at'][0]:+.2f}, {d['at'][1]:+.2f}) "
                f"yaw {d['yaw_deg']:+.0f}  {d['notes']} notes, contact max "
                f"{d['contact_error_mm_max']:.3f} mm, "
                f"penetration {d['penetration_mm']:.3f} mm"
            )
    return 0
