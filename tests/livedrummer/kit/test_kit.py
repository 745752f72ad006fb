"""Kit model: the bundled kit, mirroring, routing, pair table, and strict kit files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from livedrummer.errors import KitError
from livedrummer.kit.loader import kit_names, load_kit
from livedrummer.kit.vocabulary import Limb, PieceKind, Zone

ROCK5 = Path(__file__).resolve().parents[3] / "kits" / "rock5.toml"


def test_default_kit_is_a_right_handed_five_piece_with_cymbals() -> None:
    kit = load_kit("rock5")
    kinds = [p.kind for p in kit.pieces]
    assert kit.handedness == "right"
    assert kinds.count(PieceKind.KICK) == 1
    assert kinds.count(PieceKind.SNARE) == 1
    assert kinds.count(PieceKind.TOM) == 3
    assert kinds.count(PieceKind.CRASH) == 2
    assert {PieceKind.HIHAT, PieceKind.RIDE, PieceKind.SPLASH} <= set(kinds)
    assert kit.piece("snare").zones == (Zone.HEAD, Zone.RIM, Zone.CROSS_STICK)
    assert kit.piece("hihat").limb_for(Zone.PEDAL) is Limb.LF
    assert kit.piece("kick").preferred_limb is Limb.RF


def test_instruments_route_to_pieces() -> None:
    kit = load_kit("rock5")
    assert kit.resolve("tom5") is kit.piece("tom3")
    assert kit.resolve("china") is kit.piece("crash2")
    assert kit.resolve("cowbell") is None


def test_pair_table_is_antisymmetric() -> None:
    kit = load_kit("rock5")
    assert kit.pair("ride", "hihat") == 1.0
    assert kit.pair("hihat", "ride") == -1.0
    assert kit.pair("kick", "splash") == 0.0


def test_left_kit_is_the_default_mirrored() -> None:
    right, left = load_kit("rock5"), load_kit("rock5-left")
    assert left.handedness == "left" and left.name == "rock5-left"
    for a, b in zip(right.pieces, left.pieces, strict=True):
        assert b.position_m == (-a.position_m[0], a.position_m[1], a.position_m[2])
        assert b.preferred_limb is a.preferred_limb.mirrored
        na, nb = a.normal, b.normal
        assert np.allclose(nb, [-na[0], na[1], na[2]])
    assert left.pair("ride", "hihat") == -1.0
    assert left.piece("hihat").limb_for(Zone.PEDAL) is Limb.RF
    assert left.mirrored().pieces == right.pieces
    assert "rock5-left" in kit_names()


def test_normals_point_up_for_flat_pieces_and_at_the_drummer_for_the_kick() -> None:
    kit = load_kit("rock5")
    assert kit.piece("hihat").normal[2] > 0.99
    kick = kit.piece("kick").normal
    assert abs(kick[2]) < 1e-9 and kick[1] < -0.9  # faces the seat (-y)


def test_mirroring_an_already_left_kit_by_name_is_refused() -> None:
    with pytest.raises(KitError, match="unknown kit 'rock5-left-left'"):
        load_kit("rock5-left-left")


def _kit_with(tmp_path: Path, old: str, new: str) -> Path:
    text = ROCK5.read_text()
    assert old in text
    path = tmp_path / "mine.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "radius_m = 0.178",
            "raduis_m = 0.178",
            r"\[piece 'snare'\] raduis_m: unknown key; did you mean 'radius_m'",
        ),
        (
            "elasticity = 0.8",
            "elasticity = 2.0",
            r"\[piece 'snare'\] elasticity: must be <= 1.0 \(got 2.0\)",
        ),
        ('kind = "snare"', 'kind = "snaer"', r"kind: must be one of .*\(got 'snaer'\)"),
        ('preferred_limb = "LH"', 'preferred_limb = "left"', r"preferred_limb: must be one of"),
        (
            "position_m = [-0.07, 0.36, 0.64]",
            "position_m = [-0.07, 0.36]",
            r"position_m: expected a list of 3 numbers",
        ),
        ('pieces = ["ride", "hihat"]', 'pieces = ["ride", "hihatt"]', r"no piece named 'hihatt'"),
    ],
)
def test_kit_file_errors_name_file_table_key_and_value(
    tmp_path: Path, old: str, new: str, message: str
) -> None:
    path = _kit_with(tmp_path, old, new)
    with pytest.raises(KitError, match=message) as err:
        load_kit(str(path))
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)


def test_zone_not_on_this_kind_of_piece(tmp_path: Path) -> None:
    path = _kit_with(tmp_path, "elasticity = 0.8", 'elasticity = 0.8\nzones = ["head", "bell"]')
    with pytest.raises(KitError, match=r"zones: 'bell' is not one of head, rim, cross_stick"):
        load_kit(str(path))


def test_duplicate_piece_and_double_routing_are_errors(tmp_path: Path) -> None:
    path = _kit_with(tmp_path, 'name = "tom2"', 'name = "tom1"')
    with pytest.raises(KitError, match=r"\[piece 'tom1'\] name: another piece has this name"):
        load_kit(str(path))
    path = _kit_with(tmp_path, 'plays = ["crash2", "china"]', 'plays = ["crash2", "crash1"]')
    with pytest.raises(KitError, match="'crash1' is played by both"):
        load_kit(str(path))


def test_toml_syntax_errors_give_the_line(tmp_path: Path) -> None:
    path = _kit_with(tmp_path, "radius_m = 0.178", "radius_m = = 0.178")
    with pytest.raises(KitError, match=r"mine.toml: .*line \d+"):
        load_kit(str(path))


def test_unreadable_kit_files(tmp_path: Path) -> None:
    with pytest.raises(KitError, match="is a directory"):
        load_kit(str(tmp_path) + "/")
    bad = tmp_path / "bin.toml"
    bad.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(KitError, match="byte 0: not UTF-8"):
        load_kit(str(bad))
    with pytest.raises(KitError, match="cannot read"):
        load_kit(str(tmp_path / "missing.toml"))
    with pytest.raises(KitError, match="unknown kit 'nope'; known kits: rock5, rock5-left"):
        load_kit("nope")


def test_user_kits_are_found_on_the_search_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "kits").mkdir()
    text = ROCK5.read_text().replace('name = "rock5"', 'name = "jazz4"', 1)
    (tmp_path / "kits" / "jazz4.toml").write_text(text)
    monkeypatch.setenv("LIVEDRUMMER_PATH", str(tmp_path))
    assert load_kit("jazz4").name == "jazz4"
    assert load_kit("jazz4-left").handedness == "left"
