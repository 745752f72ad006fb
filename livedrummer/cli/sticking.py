"""``livedrummer sticking FILE.mid``: which limb plays each note, as a sheet, a text score or JSON.

The sheet is for reading; ``--format text`` is the editable text score (see
:mod:`livedrummer.sticking.score`), which ``--score`` reads back so that hand-made corrections
win over the strategy; ``--json`` is for programs. ``--lookahead-ms`` runs the online form of
the optimal strategy with that lookahead, as a live performance would get it.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from livedrummer.cli.common import Subparsers, add_command, add_kit_option, add_map_option
from livedrummer.errors import LivedrummerError
from livedrummer.kit import Kit
from livedrummer.kitfile import load_kit
from livedrummer.midifile import read_midi_file
from livedrummer.notemap import load_note_map
from livedrummer.sticking.online import stick_online
from livedrummer.sticking.result import LIMBS, NOT_PLAYED, Sticking
from livedrummer.sticking.score import read_score_file, write_score
from livedrummer.sticking.sheet import render_sheet
from livedrummer.sticking.strategy import DEFAULT_STRATEGY, STRATEGIES, assign


class StickingUsageError(LivedrummerError):
    """Options of ``livedrummer sticking`` that do not go together."""


def register(sub: Subparsers) -> None:
    p = add_command(sub, "sticking", run, "which limb plays each note of a MIDI file")
    p.add_argument("file", help="Standard MIDI File")
    add_kit_option(p)
    add_map_option(p)
    p.add_argument(
        "--strategy",
        default=DEFAULT_STRATEGY,
        choices=list(STRATEGIES),
        help=f"limb-assignment strategy (default {DEFAULT_STRATEGY})",
    )
    p.add_argument(
        "--lookahead-ms",
        type=float,
        default=None,
        metavar="L",
        help="decide online with L ms of lookahead (optimal strategy only)",
    )
    p.add_argument("--score", type=Path, help="text sticking score whose limbs are honoured")
    p.add_argument("--format", choices=("sheet", "text"), default="sheet", help="output form")
    p.add_argument("--json", action="store_true", help="print a JSON list, one object per note")


def run(args: argparse.Namespace) -> int:
    perf = read_midi_file(args.file, load_note_map(args.map))
    kit = load_kit(args.kit)
    beat_s = perf.grid.beat_s
    if args.lookahead_ms is not None:
        if args.strategy != "optimal" or args.score is not None:
            raise StickingUsageError("--lookahead-ms runs the optimal strategy, without --score")
        if not args.lookahead_ms >= 0:
            raise StickingUsageError(f"--lookahead-ms must be >= 0, not {args.lookahead_ms}")
        result = stick_online(perf.onsets, kit, args.lookahead_ms / 1000.0, beat_s=beat_s)
    else:
        explicit = None if args.score is None else read_score_file(args.score, perf.onsets)
        result = assign(perf.onsets, kit, args.strategy, beat_s=beat_s, explicit=explicit)
    if args.json:
        print(json.dumps(as_json(result, kit), indent=1))
    elif args.format == "text":
        print(write_score(result, kit, perf.map_name), end="")
    else:
        print(render_sheet(result, kit, beat_s, perf.grid.bar, perf.grid.beat_in_bar), end="")
    return 0


def as_json(result: Sticking, kit: Kit) -> list[dict[str, Any]]:
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
            }
        )
    return out
