"""``livedrummer inspect FILE.mid``: what a MIDI file holds, as a drummer reads it.

A few tempo or meter changes are listed; more (a classical piece's rubato is hundreds of tempo
events) are summarised on one line, count and range, and ``--json`` lists every one.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from .files import add_channel_option, add_map_option, read_performance
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    p = add_command(sub, "inspect", run, "summarize a MIDI file: tempo, meter, onsets per piece")
    p.add_argument("file", help="Standard MIDI File")
    add_map_option(p)
    add_channel_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    performance, _ = read_performance(args, args.file, quiet=True)  # the summary says it all
    summary = performance.summary()
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print_summary(summary)
    return 0


def print_summary(s: dict[str, Any]) -> None:
    tempos = tempo_words(s["tempos_bpm"])
    meters = meter_words(s["meters"])
    print(f"{s['file']}  (map {s['map']})")
    for warning in s.get("warnings", []):
        print(f"  warning   {warning}")
    for notice in s.get("notices", []):
        print(f"  note      {notice}")
    print(f"  duration  {s['duration_s']:.3f} s, {s['bars']} bars, {s['beats']} beats")
    print(f"  tempo     {tempos}")
    print(f"  meter     {meters}")
    print(f"  onsets    {s['onsets']}  (duplicates removed: {s['duplicates_removed']})")
    for piece, zones in s["by_piece"].items():
        detail = ", ".join(f"{zone} {n}" for zone, n in zones.items())
        print(f"    {piece:<10} {sum(zones.values()):>6}  {detail}")
    print(
        f"  controls  hi-hat pedal {s['hihat_pedal_events']}, choke {s['choke_events']}, "
        f"strike position {s['strike_position_events']}"
    )
    unknown = s["unknown_notes"]
    if unknown:
        listed = ", ".join(f"note {k} x{v}" for k, v in unknown.items())
        print(f"  UNKNOWN   {listed} (not in map {s['map']}; choose another --map)")
    else:
        print("  unknown   none")
    ignored = s.get("ignored_notes", {})
    if ignored:
        listed = ", ".join(f"note {k} x{v}" for k, v in ignored.items())
        print(f"  ignored   {listed} (no place on a drum kit; not played)")
    if not s["onsets"]:
        print("  no drum notes: nothing for the drummer to play")


#: At most this many tempos (or meters) are listed; more are summarised.
LISTED = 4


def tempo_words(tempos: list[tuple[float, float]]) -> str:
    """``120 bpm at 0.00 s, 90 bpm at 12.00 s``, or for many: ``412 tempos, 38.5-126 bpm
    (first 72 bpm at 0.00 s; --json lists them)``."""
    if len(tempos) <= LISTED:
        return ", ".join(f"{bpm:g} bpm at {t:.2f} s" for t, bpm in tempos)
    bpms = [bpm for _, bpm in tempos]
    t0, bpm0 = tempos[0]
    return (
        f"{len(tempos)} tempos, {min(bpms):.3g}-{max(bpms):.3g} bpm "
        f"(first {bpm0:.3g} bpm at {t0:.2f} s; --json lists them)"
    )


def meter_words(meters: list[tuple[float, int, int]]) -> str:
    """The meters as :func:`tempo_words` gives tempos: listed, or counted with the ones used."""
    if len(meters) <= LISTED:
        return ", ".join(f"{n}/{d} at {t:.2f} s" for t, n, d in meters)
    used = sorted({f"{n}/{d}" for _, n, d in meters}, key=lambda m: tuple(map(int, m.split("/"))))
    return f"{len(meters)} meters: {', '.join(used)} (--json lists them)"
