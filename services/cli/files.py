"""What a command reads: MIDI files through one front door, and the bundled demo groove.

Every command that reads a MIDI file calls :func:`read_performance` (``--map``, ``auto`` by
default; ``--channel``), which prints the file's report on stderr
(:meth:`~livedrummer.timeline.performance.Performance.report_lines`: warnings, channels left
out, the map ``auto`` chose, unknown and ignored notes, no drum notes), and folders are
searched by :func:`midi_files` for every MIDI suffix in any case. Imports nothing heavy at
module level.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.resources import data_dir

if TYPE_CHECKING:
    from livedrummer.midi.notemap import NoteMap
    from livedrummer.timeline.performance import Performance


DEMO_GROOVE = "grooves/gmd-drummer1-funk-80.mid"


DEMO_MAP = "roland-td"


def demo_groove() -> Path:
    """The bundled demo groove (Groove MIDI Dataset, CC BY 4.0; see kits/grooves)."""
    return data_dir("kits") / DEMO_GROOVE


def add_map_option(parser: argparse.ArgumentParser, default: str = "auto") -> None:
    """``--map``; for a file, ``auto`` (the default) picks the bundled map that knows the most
    of the file's notes and says which."""
    parser.add_argument(
        "--map",
        default=default,
        help=f"note map name or .toml path; auto: the bundled map that knows the most of the "
        f"file's notes (default {default})",
    )


def add_channel_option(parser: Any, default: str = "auto") -> None:
    """``--channel N|all``: which MIDI channel is the drums (parsed by
    :func:`livedrummer.midi.channels.parse_channel`)."""
    parser.add_argument(
        "--channel",
        default=default,
        metavar="N|all",
        help="MIDI channel 1-16 read as drums, or all; auto: channel 10 when notes are on "
        f"several channels (default {default})",
    )


#: What a folder given as input is searched for (any case).
MIDI_SUFFIXES = (".mid", ".midi", ".kar", ".rmi")


def midi_files(specs: Sequence[str]) -> list[Path]:
    """The files named, with every MIDI file (:data:`MIDI_SUFFIXES`) under each folder named."""
    from livedrummer.errors import LivedrummerError

    out: list[Path] = []
    for spec in specs:
        path = Path(spec)
        if path.is_dir():
            found = (p for p in path.rglob("*") if p.suffix.lower() in MIDI_SUFFIXES)
            out.extend(sorted(p for p in found if p.is_file()))
        else:
            out.append(path)
    if not out:
        raise LivedrummerError(f"no MIDI files ({' '.join(MIDI_SUFFIXES)}) in {', '.join(specs)}")
    return out


def report(path: Path | str, performance: Performance, note_map: NoteMap) -> None:
    """The lines every command prints on stderr about a file it read
    (:meth:`~livedrummer.timeline.performance.Performance.report_lines`)."""
    for line in performance.report_lines(note_map.ignored):
        print(f"livedrummer: {path}: {line}", file=sys.stderr)


def read_performance(
    args: argparse.Namespace, path: Path | str, default_map: str = "auto", *, quiet: bool = False
) -> tuple[Performance, NoteMap]:
    """``path`` read as ``--map`` and ``--channel`` say, its report printed (unless
    ``quiet``); the one way every file command reads its file."""
    from livedrummer.errors import ConfigError
    from livedrummer.midi.channels import parse_channel
    from livedrummer.midi.notemap import AUTO, bundled_note_maps, load_note_map
    from livedrummer.midi.smf import read_midi_file

    try:
        channel = parse_channel(getattr(args, "channel", "auto"))
    except ValueError as exc:
        raise ConfigError(f"--channel: {exc}") from None
    spec = getattr(args, "map", None) or default_map
    if spec == AUTO:
        maps = bundled_note_maps()
        performance = read_midi_file(path, maps, channel=channel)
        note_map = next(m for m in maps if m.name == performance.map_name)
    else:
        note_map = load_note_map(spec)
        performance = read_midi_file(path, note_map, channel=channel)
    if not quiet:
        report(path, performance, note_map)
    return performance, note_map
