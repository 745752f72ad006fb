"""``livedrummer check FILE.mid...``: is the drummer's motion physically true?

Animates each file on the kit (optimal limb assignment unless --sticking says otherwise) and
measures contact error at every onset, the deepest stick-tip penetration and joint-limit
violations (see :mod:`livedrummer.body.check`). Several files or folders are checked one by
one and summarised together (max over files; p99 and mean over all onsets).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.cli.common import (
    Subparsers,
    add_command,
    add_kit_option,
    add_map_option,
    add_motion_options,
)
from livedrummer.errors import LivedrummerError


def register(sub: Subparsers) -> None:
    p = add_command(sub, "check", run, "check contact, penetration and joint limits of the motion")
    p.add_argument("files", nargs="+", help="Standard MIDI File(s) or folders of them")
    add_kit_option(p)
    add_map_option(p)
    add_motion_options(p)
    p.add_argument("--fps", type=float, default=200.0, help="frames per second checked")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def midi_files(specs: list[str]) -> list[Path]:
    out: list[Path] = []
    for spec in specs:
        path = Path(spec)
        if path.is_dir():
            out.extend(sorted(path.rglob("*.mid")))
        else:
            out.append(path)
    if not out:
        raise LivedrummerError(f"no .mid files in {', '.join(specs)}")
    return out


def run(args: argparse.Namespace) -> int:
    from livedrummer.body.check import check
    from livedrummer.body.expression import load_expression
    from livedrummer.body.perform import named_sticking, perform
    from livedrummer.body.rig import build_rig
    from livedrummer.body.strokes import StrokeParams
    from livedrummer.kitfile import load_kit
    from livedrummer.midifile import read_midi_file
    from livedrummer.notemap import load_note_map

    kit = load_kit(args.kit)
    rig = build_rig(kit)
    note_map = load_note_map(args.map)
    expression = load_expression(args.preset) if args.preset else None
    strokes = StrokeParams(model=args.strokes)
    sticker = named_sticking(args.sticking)
    files = midi_files(args.files)
    errors: list[np.ndarray] = []
    worst: dict[str, Any] = {"penetration_mm": 0.0, "file": None, "at_s": 0.0}
    totals = {"notes": 0, "not_played": 0, "joint_limit_violations": 0, "frames": 0}
    by_limit: dict[str, int] = {}
    worst_contact: tuple[float, str] = (0.0, "")
    for path in files:
        done = perform(
            read_midi_file(path, note_map), rig, note_map, expression, strokes, sticking=sticker
        )
        r = check(done.animation, done.sticking, args.fps)
        errors.append(r.contact_error_m)
        for key in totals:
            totals[key] += getattr(r, key)
        for k, v in r.violations_by_limit.items():
            by_limit[k] = by_limit.get(k, 0) + v
        if r.penetration_m * 1000 > worst["penetration_mm"]:
            worst = {"penetration_mm": r.penetration_m * 1000, "file": str(path),
                     "at_s": r.penetration_at_s}  # fmt: skip
        if r.contact_error_m.size and r.contact_error_m.max() > worst_contact[0]:
            worst_contact = (float(r.contact_error_m.max()), str(path))
    e = np.concatenate(errors) * 1000.0 if errors else np.zeros(0)
    summary: dict[str, Any] = {
        "files": len(files),
        "kit": kit.name,
        "map": note_map.name,
        **totals,
        "contact_error_mm": {
            "max": round(float(e.max()), 6) if e.size else 0.0,
            "p99": round(float(np.percentile(e, 99)), 6) if e.size else 0.0,
            "mean": round(float(e.mean()), 6) if e.size else 0.0,
            "within_5mm": round(float(np.mean(e <= 5.0)), 6) if e.size else 1.0,
            "worst_file": worst_contact[1] or None,
        },
        "penetration_mm": round(worst["penetration_mm"], 4),
        "penetration_file": worst["file"],
        "penetration_at_s": round(worst["at_s"], 4),
        "violations_by_limit": by_limit,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        c = summary["contact_error_mm"]
        print(f"{len(files)} file(s), kit {kit.name}, map {note_map.name}")
        print(f"  notes checked      {summary['notes']}  (not played: {summary['not_played']})")
        print(f"  contact error mm   max {c['max']:.4f}  p99 {c['p99']:.4f}  mean {c['mean']:.4f}"
              f"  within 5 mm {c['within_5mm'] * 100:.3f} %")  # fmt: skip
        print(
            f"  penetration mm     {summary['penetration_mm']:.3f}"
            + (f"  ({worst['file']} at {worst['at_s']:.3f} s)" if worst["file"] else "")
        )
        print(f"  joint-limit hits   {summary['joint_limit_violations']} of "
              f"{summary['frames']} frames  {by_limit}")  # fmt: skip
    return 0
