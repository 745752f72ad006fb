"""The drum plugins' and the Alesis modules' maps, played: a file of every note of each table.

Each case writes, with mido, a file that strikes every note of one map's table once, in turn,
reads it with that map, and checks each onset's piece, zone and hi-hat state against the table
below. The table is written here from the makers' community tables (the sources each map file
cites), grouped by what a note plays, independently of the map file's own lines; a note the
file adds, drops or files elsewhere fails. The same file is then stuck onto rock5+percussion:
every note a map plays lands on a piece of that kit. The ``auto`` cases check which map a
plugin's file picks and that a tie names the maps tied.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import mido
import pytest

from livedrummer.kit.vocabulary import INSTRUMENTS, ZONES, HiHat
from livedrummer.midi.notemap import bundled_note_maps, load_note_map
from livedrummer.midi.smf import read_midi_file

Play = tuple[str, str, str]  # piece, zone, hi-hat state ("none" off the hi-hat)


def hh(zone: str, state: str) -> Play:
    return ("hihat", zone, state)


def p(piece: str, zone: str) -> Play:
    return (piece, zone, "none")


PEDAL = hh("pedal", "pedal")
KICK = p("kick", "head")


def toms(*rows: tuple[int, list[int], list[int]]) -> dict[Play, list[int]]:
    """tom number, its head notes, its rim notes."""
    out: dict[Play, list[int]] = {}
    for n, head, rim in rows:
        out[p(f"tom{n}", "head")] = head
        if rim:
            out[p(f"tom{n}", "rim")] = rim
    return out


ALESIS: dict[Play, list[int]] = {
    KICK: [36], p("snare", "head"): [38], p("snare", "rim"): [40],
    **toms((1, [48], [50]), (2, [45], [47]), (3, [43], [58]), (4, [41], [39])),
    hh("bow", "open"): [46], hh("bow", "half"): [23], hh("bow", "closed"): [42], PEDAL: [44, 21],
    p("crash1", "bow"): [49], p("crash2", "bow"): [57], p("ride", "bow"): [51],
}  # fmt: skip

#: map name -> (what each note plays, the notes listed as ignored)
TABLES: dict[str, tuple[dict[Play, list[int]], list[int]]] = {
    "ezdrummer3": (
        {
            p("percussion", "head"): [1, 2],
            p("tambourine", "head"): [3],
            KICK: [34, 35, 36],
            p("snare", "head"): [6, 33, 38, 39, 66, 68, 69, 70, 125],
            p("snare", "cross_stick"): [37, 67, 127],
            p("snare", "rim"): [40, 71, 76, 126],
            hh("edge", "closed"): [7, 18, 20, 22, 62, 65, 122],
            hh("bow", "closed"): [8, 9, 11, 19, 42, 61, 63, 119],
            PEDAL: [10, 21, 23, 44],
            hh("bow", "half"): [12, 13, 24, 64, 120],
            hh("bow", "open"): [14, 15, 16, 17, 25, 26, 46, 60, 121, 123, 124],
            **toms(
                (1, [48], [81, 82]),
                (2, [47], [79, 80]),
                (3, [45], [77, 78]),
                (4, [43], [74, 75]),
                (5, [41], [72, 73]),
            ),
            p("crash1", "edge"): [32, 55, 56, 57, 58, 83, 86, 103, 106, 107],  # crashes 1 and 3
            p("crash1", "bow"): [31, 84, 87, 101],
            p("crash2", "edge"): [28, 49, 50, 91, 94, 95, 98, 99],  # crashes 2 and 4
            p("crash2", "bow"): [27, 89, 96],
            p("ride", "bow"): [29, 51, 104, 108, 111, 113, 116],
            p("ride", "edge"): [52, 54, 59, 110, 115, 118],
            p("ride", "bell"): [30, 53, 85, 88, 90, 92, 93, 97, 100, 102, 105, 109, 112, 114, 117],
        },
        [],
    ),
    "ezdrummer2": (
        {
            p("percussion", "head"): [1, 2],
            p("tambourine", "head"): [3],
            KICK: [34, 35, 36],
            p("snare", "cross_stick"): [4, 5, 37, 67, 76, 127],
            p("snare", "head"): [6, 33, 38, 39, 66, 68, 69, 70, 125],
            p("snare", "rim"): [40, 71, 126],
            hh("edge", "closed"): [7, 18, 22, 62, 64, 122],
            hh("bow", "closed"): [8, 9, 11, 19, 20, 42, 61, 63, 65, 119],
            PEDAL: [10, 21, 23, 44],
            hh("bow", "half"): [12, 13, 24, 120, 123],
            hh("bow", "open"): [14, 15, 16, 17, 25, 26, 46, 60, 121, 124],
            **toms(
                (1, [48, 81], [82]),
                (2, [47, 79], [80]),
                (3, [45, 77], [78]),
                (4, [43, 74], [75]),
                (5, [41, 72], [73]),
            ),
            p("crash1", "edge"): [31, 32, 55, 56, 57, 58, 94, 106],  # cymbals 1 and 3
            p("crash2", "edge"): [27, 28, 49, 50, 52, 54, 95, 107],  # cymbals 2 and 4
            p("ride", "edge"): [29, 30, 59, 83, 86, 91, 98, 103, 110, 115, 118],
            p("ride", "bow"): [51, 84, 87, 89, 92, 96, 99, 101, 104, 108, 111, 113, 116],
            p("ride", "bell"): [53, 85, 88, 90, 93, 97, 100, 102, 105, 109, 112, 114, 117],
        },
        [],
    ),
    "superior3": (
        {
            p("snare", "cross_stick"): [1, 2, 3, 37, 67, 76, 127],  # 67, 76, 127: the majority
            p("snare", "head"): [4, 6, 33, 38, 39, 66, 68, 69, 70, 125, 126],
            p("snare", "rim"): [40, 71],
            KICK: [34, 35, 36],
            hh("edge", "closed"): [7, 18, 22, 62],
            hh("bow", "closed"): [8, 11, 19, 42, 61, 63, 65],
            hh("bell", "closed"): [9, 20, 119],
            PEDAL: [10, 21, 23, 44],
            hh("bow", "half"): [12, 13],
            hh("bow", "open"): [14, 15, 16, 17],
            hh("edge", "half"): [24, 64],
            hh("edge", "open"): [25, 26, 46, 60],
            hh("bell", "half"): [120, 121],
            hh("bell", "open"): [122, 123, 124],
            **toms(
                (1, [48], [81, 82]),
                (2, [47], [79, 80]),
                (3, [45], [77, 78]),
                (4, [43], [74, 75]),
                (5, [41], [72, 73]),
            ),
            p("crash1", "edge"): [55, 56, 83, 86, 95, 98],
            p("crash1", "bow"): [84, 87, 96, 99],
            p("crash1", "bell"): [85, 88, 97, 100],
            p("crash2", "edge"): [49, 50, 57, 58, 91, 94, 103, 106],
            p("crash2", "bow"): [27, 31, 89, 92, 101, 104],
            p("crash2", "bell"): [28, 32, 90, 93, 102, 105],
            p("china", "edge"): [52, 54, 107, 110],
            p("china", "bow"): [108, 111],
            p("china", "bell"): [109, 112],
            p("ride", "bow"): [29, 51, 113, 116],
            p("ride", "bell"): [30, 53, 114, 117],
            p("ride", "edge"): [59, 115, 118],
        },
        [],
    ),
    "addictive2": (
        {
            KICK: [36],
            p("snare", "rim"): [37, 39, 41, 44],
            p("snare", "head"): [38, 40, 43, 101],
            p("snare", "cross_stick"): [42],
            p("ride", "bow"): [45, 60, 84],
            p("ride", "bell"): [61, 85],
            p("ride", "edge"): [62, 86],
            p("crash1", "edge"): [46, 77, 81],
            p("crash2", "edge"): [79, 89, 93],
            p("china", "edge"): [91],
            p("cowbell", "head"): [47],
            PEDAL: [48, 59],
            hh("bow", "closed"): [49, 51],
            hh("edge", "closed"): [50, 52],
            hh("bell", "closed"): [53],
            hh("bow", "half"): [54, 55],
            hh("bow", "open"): [56, 57],
            hh("bell", "half"): [58],
            **toms((1, [71], [72]), (2, [69], [70]), (3, [67], [68]), (4, [65], [66])),
        },
        [63, 75, 78, 80, 82, 87, 90, 92, 94],
    ),  # stop, hand only; sticks
    "ssd5": (
        {
            **toms(
                (1, [48], [19]), (2, [47], [17]), (3, [45], [16]), (4, [43], [14]), (5, [41], [12])
            ),
            p("snare", "head"): [21, 34, 38],
            p("snare", "rim"): [33, 39, 40],
            p("snare", "cross_stick"): [37],
            KICK: [35, 36],
            hh("edge", "closed"): [22, 26, 60, 61],
            hh("bow", "closed"): [42, 46, 66, 67],
            hh("edge", "half"): [62, 63],
            hh("edge", "open"): [64, 65],
            hh("bow", "half"): [68, 69],
            hh("bow", "open"): [70, 71],
            PEDAL: [44, 72, 73],
            p("crash1", "edge"): [27, 28, 54, 55],
            p("crash1", "bow"): [91, 95],
            p("crash2", "edge"): [29, 30, 56, 57],
            p("crash2", "bow"): [92, 94],
            p("china", "edge"): [31, 32],
            p("china", "bow"): [93],
            p("splash", "edge"): [49, 50],
            p("splash", "bow"): [90],
            p("ride", "bow"): [51, 52],
            p("ride", "bell"): [53, 83, 84],
            p("ride", "edge"): [58, 59],
            p("cowbell", "head"): [74, 75],
            p("percussion", "head"): [76, 80, 81, 82],
            p("tambourine", "head"): [77, 78, 79],
        },
        [],
    ),
    "mt-powerdrumkit": (
        {
            KICK: [33, 35, 36],
            p("snare", "cross_stick"): [37],
            p("snare", "head"): [38, 39, 40],
            **toms((1, [48, 50], []), (2, [45, 47], []), (3, [41, 43], [])),
            hh("bow", "closed"): [42, 62, 63],
            hh("bow", "half"): [44, 61],
            hh("bow", "open"): [46, 60],
            PEDAL: [65],
            p("crash1", "edge"): [49],
            p("crash2", "edge"): [57, 58],
            p("ride", "bow"): [51],
            p("ride", "bell"): [53],
            p("china", "edge"): [52],
            p("splash", "edge"): [55],
        },
        [],
    ),
    "alesis-surge": (ALESIS, []),
    "alesis-nitro": (ALESIS, []),
}


def every_note_file(path: Path, notes: list[int]) -> Path:
    """One stroke of each note, a quarter note apart, on channel 10."""
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000)])
    for i, n in enumerate(notes):
        track.append(
            mido.Message("note_on", channel=9, note=n, velocity=90, time=0 if i == 0 else 470)
        )
        track.append(mido.Message("note_on", channel=9, note=n, velocity=0, time=10))
    mid = mido.MidiFile(ticks_per_beat=480)
    mid.tracks.append(track)
    mid.save(path)
    return path


@pytest.mark.parametrize("name", sorted(TABLES))
def test_every_note_of_the_table_plays_its_piece_and_zone(tmp_path: Path, name: str) -> None:
    plays, ignored = TABLES[name]
    expect = {n: play for play, notes in plays.items() for n in notes}
    assert len(expect) == sum(len(v) for v in plays.values()), "a note listed twice"
    notes = sorted([*expect, *ignored])
    path = every_note_file(tmp_path / f"{name}.mid", notes)
    perf = read_midi_file(path, load_note_map(name))
    assert perf.stats.unknown_notes == Counter()
    assert perf.stats.ignored_notes == Counter(dict.fromkeys(ignored, 1))
    got = {
        int(o["note"]): (
            INSTRUMENTS[o["instrument"]],
            ZONES[o["zone"]].value,
            list(HiHat)[o["hihat"]].value,
        )
        for o in perf.onsets
    }
    assert perf.onsets.size == len(expect)
    assert got == expect
    nm = load_note_map(name)
    assert set(nm.notes) == set(expect) and set(nm.ignored) == set(ignored)  # nothing extra


@pytest.mark.parametrize("name", sorted(TABLES))
def test_every_played_note_lands_on_a_piece_of_rock5_percussion(tmp_path: Path, name: str) -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.sticking.result import NOT_PLAYED
    from livedrummer.sticking.strategy import stick_performance

    plays, _ = TABLES[name]
    notes = sorted(n for ns in plays.values() for n in ns)
    perf = read_midi_file(every_note_file(tmp_path / "all.mid", notes), load_note_map(name))
    result = stick_performance(perf, load_kit("rock5+percussion"), "optimal")
    unplayed = [
        int(perf.onsets["note"][i]) for i in range(perf.onsets.size) if result.limb[i] == NOT_PLAYED
    ]
    assert unplayed == []


def test_plugin_maps_cite_community_sources_to_check_in_the_plugin() -> None:
    for name in ("ezdrummer3", "ezdrummer2", "superior3", "addictive2", "ssd5", "mt-powerdrumkit"):
        nm = load_note_map(name)
        text = " ".join(Path(nm.source).read_text().split())
        assert "community table" in text and "MIDI-map view" in text, name
        assert nm.sources and all("commit" in s for s in nm.sources), name
    assert "majority" in Path(load_note_map("superior3").source).read_text()
    assert "majority" in Path(load_note_map("addictive2").source).read_text()
    for nm in bundled_note_maps():
        assert nm.sources, nm.name


# ---- auto ------------------------------------------------------------------------------------


def groove(path: Path, bars: list[list[int]]) -> Path:
    """Each inner list is struck together, an eighth note apart."""
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000)])
    gap = 0
    for chord in bars:
        for j, n in enumerate(chord):
            track.append(
                mido.Message("note_on", channel=9, note=n, velocity=90, time=gap if j == 0 else 0)
            )
        for j, n in enumerate(chord):
            track.append(
                mido.Message("note_on", channel=9, note=n, velocity=0, time=10 if j == 0 else 0)
            )
        gap = 230
    mid = mido.MidiFile(ticks_per_beat=480)
    mid.tracks.append(track)
    mid.save(path)
    return path


def test_an_ezdrummer3_file_picks_ezdrummer3_and_names_the_tied_maps(tmp_path: Path) -> None:
    # EZdrummer 3's hi-hat articulations on 7-26, the kick on 36, its snare on 38
    hats = list(range(7, 27))
    chords = [
        [hats[i % len(hats)]] + ([36] if i % 4 == 0 else [38] if i % 4 == 2 else [])
        for i in range(64)
    ]
    perf = read_midi_file(groove(tmp_path / "ezd3.mid", chords), bundled_note_maps())
    assert perf.map_name == "ezdrummer3"
    assert perf.stats.unknown_notes == Counter()
    line = next(n for n in perf.notices if n.startswith("map auto:"))
    total = sum(len(c) for c in chords)
    assert line == (
        f"map auto: ezdrummer3 knows {total} of {total} drum notes, tied with "
        "superior3, ezdrummer2 (ezdrummer3 preferred: the smallest table, 125 notes)"
    )
    hats_read = perf.onsets[perf.onsets["instrument"] == INSTRUMENTS.index("hihat")]
    assert hats_read.size == len(chords)  # every 7-26 note is the hi-hat


def test_a_general_midi_file_stays_general_midi_and_says_what_it_tied(tmp_path: Path) -> None:
    chords = [[42, 36], [42], [42, 38], [46], [42, 36], [44], [51, 38], [49, 57]] * 4
    perf = read_midi_file(groove(tmp_path / "gm.mid", chords), bundled_note_maps())
    assert perf.map_name == "general-midi"
    line = next(n for n in perf.notices if n.startswith("map auto:"))
    tied = line.split("tied with ")[1].split(" (")[0].split(", ")
    # tied: every other map that knows all eight notes, counted from the maps themselves
    knows_all = [
        m.name
        for m in bundled_note_maps()
        if not m.chart
        and m.name != "general-midi"
        and all(m.knows(n) for n in (36, 38, 42, 44, 46, 49, 51, 57))
    ]
    assert tied == knows_all and "ezdrummer3" in tied and "yamaha-dtx" not in tied
    assert line.endswith("(general-midi preferred: General MIDI goes first)")


def test_a_gm_file_with_one_stray_note_is_not_read_as_a_plugin_map(tmp_path: Path) -> None:
    # GS's snare roll (25) once among 301 notes: ezdrummer3 knows it, GM does not
    chords = [[42, 36], [42], [42, 38], [63]] * 50 + [[25]]
    perf = read_midi_file(groove(tmp_path / "gs.mid", chords), bundled_note_maps())
    assert perf.map_name == "general-midi"
    assert perf.stats.unknown_notes == Counter({25: 1})
    line = next(n for n in perf.notices if n.startswith("map auto:"))
    assert line.startswith("map auto: general-midi knows 300 of 301 drum notes; ezdrummer3 ")
    assert "within 1% of it, so General MIDI is kept" in line
    # 5 of 305 (more than 1 %) off General MIDI: the plugin map is chosen
    chords = [[42, 36], [42], [42, 38], [63]] * 50 + [[25]] * 5
    perf = read_midi_file(groove(tmp_path / "ezd.mid", chords), bundled_note_maps())
    assert perf.map_name == "ezdrummer3"


def test_alesis_nitro_and_surge_tie_and_the_line_says_so(tmp_path: Path) -> None:
    chords = [[23, 36], [23], [42, 38], [21]] * 8  # half-open hi-hat 23, foot splash 21
    perf = read_midi_file(groove(tmp_path / "nitro.mid", chords), bundled_note_maps())
    assert perf.map_name == "alesis-nitro"
    line = next(n for n in perf.notices if n.startswith("map auto:"))
    assert "tied with alesis-surge, " in line
    assert line.endswith("(alesis-nitro preferred: the smallest table, then by name)")


def test_kits_lists_each_map_with_its_sources() -> None:
    import subprocess
    import sys

    proc = subprocess.run(
        [sys.executable, "-m", "services", "kits"], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    for nm in bundled_note_maps():
        at = next(i for i, line in enumerate(lines) if line.startswith(f"  {nm.name} "))
        assert nm.description in lines[at]
        listed = lines[at + 1 : at + 1 + len(nm.sources)]
        assert [line.split("source: ", 1)[1] for line in listed] == list(nm.sources)
