"""The ``livedrummer`` command: one entry point, one subcommand per job.

The CLI is an I/O edge: it parses arguments, calls the library, prints, and turns every
:class:`~livedrummer.errors.LivedrummerError` into one line on stderr and exit status 2 (no
traceback: a show technician needs the file and the problem, not a stack). Subcommands that
start processes or open devices import their service modules lazily, so ``inspect`` stays fast
and works where no audio or GPU library can load.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from livedrummer import __version__
from livedrummer.errors import LivedrummerError
from livedrummer.resources import data_dir

EXIT_USAGE = 2
DEMO_GROOVE = "grooves/gmd-drummer1-funk-80.mid"


def demo_groove() -> Path:
    """The bundled demo groove (Groove MIDI Dataset, CC BY 4.0; see kits/grooves)."""
    return data_dir("kits") / DEMO_GROOVE


def _cmd_inspect(args: argparse.Namespace) -> int:
    from livedrummer.midifile import read_midi_file
    from livedrummer.notemap import load_note_map

    perf = read_midi_file(args.file, load_note_map(args.map))
    summary = perf.summary()
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    _print_summary(summary)
    return 0


def _print_summary(s: dict[str, object]) -> None:
    tempos = ", ".join(f"{bpm:g} bpm at {t:.2f} s" for t, bpm in s["tempos_bpm"])  # type: ignore[attr-defined]
    meters = ", ".join(f"{n}/{d} at {t:.2f} s" for t, n, d in s["meters"])  # type: ignore[attr-defined]
    print(f"{s['file']}  (map {s['map']})")
    print(f"  duration  {s['duration_s']:.3f} s, {s['bars']} bars, {s['beats']} beats")
    print(f"  tempo     {tempos}")
    print(f"  meter     {meters}")
    print(f"  onsets    {s['onsets']}  (duplicates removed: {s['duplicates_removed']})")
    for piece, zones in s["by_piece"].items():  # type: ignore[attr-defined]
        detail = ", ".join(f"{zone} {n}" for zone, n in zones.items())
        print(f"    {piece:<10} {sum(zones.values()):>6}  {detail}")
    print(
        f"  controls  hi-hat pedal {s['hihat_pedal_events']}, choke {s['choke_events']}, "
        f"strike position {s['strike_position_events']}"
    )
    unknown = s["unknown_notes"]
    if unknown:
        listed = ", ".join(f"note {k} x{v}" for k, v in unknown.items())  # type: ignore[attr-defined]
        print(f"  UNKNOWN   {listed} (not in map {s['map']}; choose another --map)")
    else:
        print("  unknown   none")


def _cmd_kits(args: argparse.Namespace) -> int:
    from livedrummer.catalog import entries
    from livedrummer.kitfile import load_kit
    from livedrummer.notemap import load_note_map

    print("kits:")
    for name in sorted(entries("kits")):
        for variant in (name, None):
            try:
                kit = load_kit(name)
            except LivedrummerError as exc:
                print(f"  {name:<16} ERROR {exc}")
                break
            if variant is None:
                mirror = f"{name}-{'left' if kit.handedness == 'right' else 'right'}"
                print(f"  {mirror:<16} {kit.name} mirrored ({len(kit.pieces)} pieces)")
            else:
                print(f"  {name:<16} {kit.description} [{kit.source}]")
    print("note maps:")
    for name, entry in sorted(entries("kits/maps").items()):
        try:
            nm = load_note_map(str(entry.path))
            print(f"  {name:<16} {nm.description} ({len(nm.notes)} notes) [{entry.path}]")
        except LivedrummerError as exc:
            print(f"  {name:<16} ERROR {exc}")
    return 0


def _cmd_demo(args: argparse.Namespace) -> int:
    groove = demo_groove()
    print(f"demo: {groove.name} (Groove MIDI Dataset, CC BY 4.0)")
    ns = argparse.Namespace(file=str(groove), map="roland-td", json=False)
    return _cmd_inspect(ns)


def _cmd_bench(args: argparse.Namespace) -> int:
    import importlib

    module = importlib.import_module(f"bench.{args.name}")
    result: int = module.main(args.rest)
    return result


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="livedrummer",
        description="Turn an electronic drum kit or a MIDI file into a 3D virtual drummer.",
    )
    parser.add_argument("--version", action="version", version=f"livedrummer {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log more detail")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def add(
        name: str, func: Callable[[argparse.Namespace], int], help_: str
    ) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_, description=help_)
        p.set_defaults(func=func)
        return p

    p = add("inspect", _cmd_inspect, "summarize a MIDI file: tempo, meter, onsets per piece")
    p.add_argument("file", help="Standard MIDI File")
    p.add_argument("--map", default="general-midi", help="note map name or .toml path")
    p.add_argument("--json", action="store_true", help="print one JSON object")

    add("kits", _cmd_kits, "list kits and note maps")
    add("demo", _cmd_demo, "run the pipeline on the bundled demo groove")

    p = add("bench", _cmd_bench, "run a benchmark and print its figures")
    p.add_argument("name", choices=["ingest"], help="which benchmark")
    p.add_argument("rest", nargs=argparse.REMAINDER, help="benchmark options")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING,
        format="livedrummer: %(levelname)s: %(message)s",
    )
    try:
        code: int = args.func(args)
    except LivedrummerError as exc:
        print(f"livedrummer: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return 0
    except KeyboardInterrupt:
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
