"""``livedrummer sticking FILE.mid``: which limb plays each note, as a sheet, a text score or JSON.

The sheet is for reading; ``--format text`` is the editable text score (see
:mod:`livedrummer.sticking.score`), which ``--score`` reads back so that hand-made corrections
win over the strategy; ``--json`` is for programs. ``--lookahead-ms`` runs the online form of
the optimal strategy with that lookahead, as a live performance would get it. The limbs come
from :func:`livedrummer.sticking.stick_performance`, the entry point every animating command
(render, display, check, export) also uses, so what this prints is what the drummer plays.
Notes too hard to play (too fast for one hand, arms crossed) are marked on the sheet and
explained after their bar, and flagged per note in the JSON
(:func:`livedrummer.sticking.metrics.hard_notes`).
"""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING, Any

from .files import add_channel_option, add_map_option, read_performance
from .parsing import Subparsers, add_command
from .performer import add_kit_option, add_sticking_options

if TYPE_CHECKING:
    from livedrummer.kit.model import Kit
    from livedrummer.sticking.result import Sticking


def register(sub: Subparsers) -> None:
    p = add_command(sub, "sticking", run)
    p.add_argument("file", help="Standard MIDI File")
    add_kit_option(p)
    add_map_option(p)
    add_channel_option(p)
    add_sticking_options(p)
    p.add_argument(
        "--lookahead-ms",
        type=float,
        default=None,
        metavar="L",
        help="decide online with L ms of lookahead, optimal strategy only (default: offline, "
        "the whole file known)",
    )
    p.add_argument("--format", choices=("sheet", "text"), default="sheet", help="output form")
    p.add_argument("--json", action="store_true", help="print a JSON list, one object per note")


def run(args: argparse.Namespace) -> int:
    from livedrummer.kit.loader import load_kit
    from livedrummer.sticking.score import write_score
    from livedrummer.sticking.sheet import render_sheet
    from livedrummer.sticking.strategy import stick_performance

    perf, _ = read_performance(args, args.file)
    if not perf.onsets.size:  # said on stderr; nothing to stick
        if args.json:
            print("[]")
        return 0
    kit = load_kit(args.kit)
    lookahead_s = None if args.lookahead_ms is None else args.lookahead_ms / 1000.0
    result = stick_performance(perf, kit, args.sticking, score=args.score, lookahead_s=lookahead_s)
    if args.json:
        print(json.dumps(as_json(result, kit), indent=1))
    elif args.format == "text":
        print(write_score(result, kit, perf.map_name), end="")
    else:
        grid = perf.grid
        print(render_sheet(result, kit, grid.beat_s, grid.bar, grid.beat_in_bar), end="")
    return 0


def as_json(result: Sticking, kit: Kit) -> list[dict[str, Any]]:
    """One object per note: time, note, piece, limb, why it is substituted or not played, and
    whether it is too fast for one hand or played with the arms crossed (``hard`` says how)."""
    from livedrummer.sticking.metrics import crossings, hard_notes, too_fast
    from livedrummer.sticking.result import LIMBS, NOT_PLAYED

    fast, crossed, hard = too_fast(result, kit), crossings(result, kit), hard_notes(result, kit)
    out = []
    on = result.onsets
    for i in range(on.size):
        p = int(result.piece[i])
        code = int(result.limb[i])
        out.append(
            {
                "time_s": float(on["time_s"][i]),
                "note": int(on["note"][i]),
                "piece": kit.pieces[p].name if p >= 0 else None,
                "limb": None if code == NOT_PLAYED else LIMBS[code].value,
                "reason": result.reasons.get(i),
                "too_fast": bool(fast[i]),
                "crossed": bool(crossed[i]),
                "hard": hard.get(i),
            }
        )
    return out
