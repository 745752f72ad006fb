"""Note maps: bundled maps cover what they claim; map files are checked strictly."""

from __future__ import annotations

from pathlib import Path

import pytest

from livedrummer.errors import NoteMapError
from livedrummer.kit.vocabulary import HiHat, Zone
from livedrummer.midi.notemap import load_note_map, note_map_names

MAPS = Path(__file__).resolve().parents[3] / "kits" / "maps"


def test_bundled_maps() -> None:
    assert note_map_names() == [
        "addictive2",
        "alesis-nitro",
        "alesis-surge",
        "ezdrummer2",
        "ezdrummer3",
        "general-midi",
        "mt-powerdrumkit",
        "rock-band-chart",
        "roland-td",
        "ssd5",
        "superior3",
        "yamaha-dtx",
        "yamaha-dtx502",
    ]


def test_general_midi_covers_every_percussion_note() -> None:
    gm = load_note_map("general-midi")
    assert sorted(gm.notes) == list(range(35, 88))  # GM1 35-81, GM2/GS hand percussion 82-87
    assert sorted(gm.ignored) == list(range(27, 35))  # GM2/GS sticks, clicks, scratches
    assert gm.ignored[33] == "Metronome click" and gm.lookup(33) is None
    assert gm.lookup(82).instrument == "percussion"  # type: ignore[union-attr]
    assert gm.lookup(42).hihat is HiHat.CLOSED  # type: ignore[union-attr]
    assert gm.lookup(44).zone is Zone.PEDAL  # type: ignore[union-attr]
    assert gm.lookup(53).zone is Zone.BELL  # type: ignore[union-attr]


def test_roland_td_map_matches_the_td11_layout_with_tom4_and_aux() -> None:
    td = load_note_map("roland-td")
    expect = {
        36: ("kick", "head"), 38: ("snare", "head"), 40: ("snare", "rim"),
        37: ("snare", "cross_stick"), 48: ("tom1", "head"), 50: ("tom1", "rim"),
        45: ("tom2", "head"), 47: ("tom2", "rim"), 43: ("tom3", "head"), 58: ("tom3", "rim"),
        46: ("hihat", "bow"), 26: ("hihat", "edge"), 42: ("hihat", "bow"), 22: ("hihat", "edge"),
        44: ("hihat", "pedal"), 49: ("crash1", "bow"), 55: ("crash1", "edge"),
        57: ("crash2", "bow"), 52: ("crash2", "edge"), 51: ("ride", "bow"), 59: ("ride", "edge"),
        53: ("ride", "bell"),
        41: ("tom4", "head"), 39: ("tom4", "rim"),  # larger modules' tom 4
        27: ("percussion", "head"), 28: ("percussion", "head"),  # TD-17 AUX head/rim
    }  # fmt: skip
    got = {n: (s.instrument, s.zone.value) for n, s in td.notes.items()}
    assert got == expect
    assert td.lookup(26).hihat is HiHat.OPEN and td.lookup(22).hihat is HiHat.CLOSED  # type: ignore[union-attr]
    assert td.hihat_cc_closed == 90
    assert td.openness(0) == 1.0 and td.openness(90) == 0.0 and td.openness(127) == 0.0
    assert td.openness(45) == pytest.approx(0.5)


def test_dtx502_map_follows_the_reference_manual_table() -> None:
    dtx = load_note_map("yamaha-dtx502")
    assert {
        n: (s.instrument, s.zone.value)
        for n, s in dtx.notes.items()
        if n in (36, 38, 59, 49, 78, 85, 83, 35)
    } == {
        36: ("kick", "head"),
        38: ("snare", "head"),
        59: ("crash1", "bow"),
        49: ("crash1", "edge"),
        78: ("hihat", "edge"),
        85: ("hihat", "bell"),
        83: ("hihat", "pedal"),
        35: ("kick", "head"),
    }
    assert "DTX502 Reference Manual" in Path(dtx.source).read_text()  # the source is cited


def test_every_bundled_map_cites_its_source() -> None:
    from livedrummer.midi.notemap import bundled_note_maps

    for m in bundled_note_maps():
        assert "Source" in Path(m.source).read_text(), m.name


def test_vendor_maps_use_their_own_numbers() -> None:
    assert load_note_map("yamaha-dtx").lookup(31).instrument == "snare"  # type: ignore[union-attr]
    assert load_note_map("yamaha-dtx").lookup(33).instrument == "kick"  # type: ignore[union-attr]
    assert load_note_map("alesis-nitro").lookup(23).hihat is HiHat.HALF  # type: ignore[union-attr]


def _map_with(tmp_path: Path, old: str, new: str, name: str = "roland-td") -> Path:
    text = (MAPS / "roland-td.toml").read_text()
    assert old in text
    path = tmp_path / f"{name}.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('piece = "kick"', 'piece = "kik"', r"\[notes.36\] piece: must be one of .*\(got 'kik'\)"),
        ('piece = "kick", zone = "head"', 'piece = "kick", zone = "bell"', r"kick has zones head \(got 'bell'\)"),
        ("hihat_cc_closed = 90", "hihat_cc_closed = 900", r"hihat_cc_closed: must be <= 127"),
        ("36 = {", "136 = {", r"\[notes\] 136: note keys must be MIDI note numbers"),
        ('piece = "kick", zone = "head"', 'piece = "kick", zone = "head", velo = 3', r"velo: unknown key"),
    ],
)  # fmt: skip
def test_map_file_errors(tmp_path: Path, old: str, new: str, message: str) -> None:
    path = _map_with(tmp_path, old, new)
    with pytest.raises(NoteMapError, match=message) as err:
        load_note_map(str(path))
    assert str(path) in str(err.value)


def test_map_name_must_match_file_name(tmp_path: Path) -> None:
    path = _map_with(tmp_path, "", "", name="mine")
    with pytest.raises(NoteMapError, match=r"name: must equal the file name 'mine'"):
        load_note_map(str(path))


def test_unknown_map_lists_known_ones() -> None:
    with pytest.raises(
        NoteMapError, match="unknown note map 'td30'; known maps: addictive2, alesis"
    ):
        load_note_map("td30")


def test_the_chart_map_follows_the_chart_format_table() -> None:
    chart = load_note_map("rock-band-chart")
    assert chart.lookup(101).instrument == "tom3"  # type: ignore[union-attr]  # 5-lane green
    assert chart.ignored[109] == "Flam marker"
    assert {65, 77, 89} <= set(chart.ignored)  # 5-lane green of Easy, Medium, Hard
    assert "1 lane" in chart.ignored[126] and "2 lanes" in chart.ignored[127]


def test_map_sources_must_be_a_list_of_strings(tmp_path: Path) -> None:
    path = _map_with(tmp_path, "sources = [", "sources = 3\nsourcez = [")
    with pytest.raises(NoteMapError, match=r"sources: expected a list of strings"):
        load_note_map(str(path))
