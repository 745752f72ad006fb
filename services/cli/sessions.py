"""``livedrummer sessions list|export``: the journaled sessions, and their export to MIDI."""

from __future__ import annotations

import argparse
from pathlib import Path

from .parsing import Subparsers, add_command, add_renamed


def register(sub: Subparsers) -> None:
    p = add_command(sub, "sessions", _usage)
    add_renamed(
        p,
        "--dir",
        p.add_argument(
            "--sessions-dir",
            type=Path,
            metavar="DIR",
            help="journal folder, as for input (default $LIVEDRUMMER_HOME/sessions)",
        ),
    )
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    ls = actions.add_parser("list", help="one line per session")
    ls.set_defaults(func=run_list)
    ex = actions.add_parser("export", help="write a session as a Standard MIDI File")
    ex.add_argument("session", help="session id, unique id prefix, or journal path")
    ex.add_argument("-o", "--output", type=Path, required=True, help="output .mid file")
    ex.add_argument(
        "--tempo",
        type=float,
        metavar="BPM",
        help="one file tempo in bpm (default: the tempo map the live beat tracker "
        "detects in the playing; 120 when it finds no beat)",
    )
    ex.set_defaults(func=run_export)


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer sessions {list,export} ...")
    return 2


def run_list(args: argparse.Namespace) -> int:
    from ..input.journal import list_sessions, sessions_dir

    infos = list_sessions(args.sessions_dir)
    if not infos:
        print(f"no sessions in {args.sessions_dir or sessions_dir()}")
        return 0
    for i in infos:
        state = "closed" if i.clean else "open/crashed"
        if i.discarded_bytes:
            state += f", {i.discarded_bytes} torn bytes skipped"
        source = i.meta.get("source", "?")
        print(
            f"{i.session}  {i.onsets:>7} onsets  {i.controls:>6} controls  "
            f"{i.duration_s:>8.1f} s  {source}  ({state})"
        )
    return 0


def run_export(args: argparse.Namespace) -> int:
    from ..input.journal import export_session, find_session

    path = find_session(args.session, args.sessions_dir)
    detect = args.tempo is None
    journal = export_session(path, args.output, bpm=120.0 if detect else args.tempo, detect=detect)
    print(f"{args.output}: {journal.onsets.size} onsets, {journal.controls.size} controls")
    if journal.stop_reason:
        print(f"  note: {journal.stop_reason}; {journal.discarded_bytes} bytes skipped")
    return 0
