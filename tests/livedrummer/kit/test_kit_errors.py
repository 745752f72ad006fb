"""Bad kits and note maps: wrong types, unknown keys, pieces the drummer cannot reach.

Each case edits one line of a bundled file and expects one error line naming the file, the
table (piece) and the key; reach is checked against the body's own dimensions.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from livedrummer.body.rig import build_rig, neutral_world
from livedrummer.body.secondary import SecondaryParams
from livedrummer.body.skeleton import J, build_skeleton
from livedrummer.errors import ConfigError, KitError, NoteMapError, UnreachableError
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map

REPO = Path(__file__).resolve().parents[3]
KIT = (REPO / "kits" / "rock5.toml").read_text()
MAP = (REPO / "kits" / "maps" / "roland-td.toml").read_text()
SNARE_AT = "position_m = [-0.07, 0.36, 0.64]"
KICK_PEDAL_AT = "pedal_position_m = [0.10, 0.38, 0.02]"


def edited(tmp_path: Path, text: str, old: str, new: str, name: str) -> Path:
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def expect(error: type[ConfigError], load: object, path: Path, pattern: str) -> str:
    assert callable(load)
    with pytest.raises(error, match=pattern) as err:
        load(str(path))
    message = str(err.value)
    assert message.startswith(f"{path}: ") and "\n" not in message, message
    return message


# ---- kits: wrong types and unknown keys ------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        ("radius_m = 0.178", "radius_m = true", r"\[piece 'snare'\] radius_m: expected a number \(got True\)"),
        ("seat_height_m = 0.52", 'seat_height_m = "low"', r"\[kit\] seat_height_m: expected a number"),
        ('handedness = "right"', "handedness = 1", r"\[kit\] handedness: expected a string \(got 1\)"),
        ("elasticity = 0.8", 'elasticity = 0.8\nzones = "head"', r"\[piece 'snare'\] zones: expected a list of strings"),
        ("elasticity = 0.8", "elasticity = 0.8\nplays = [1]", r"\[piece 'snare'\] plays: expected a list of strings"),
        (SNARE_AT, 'position_m = [-0.07, "a", 0.64]', r"\[piece 'snare'\] position_m: expected a number \(got 'a'\)"),
        (SNARE_AT, "position_m = [-0.07, nan, 0.64]", r"\[piece 'snare'\] position_m: expected a finite number"),
        ("double_pedal = false", 'double_pedal = "no"', r"\[piece 'kick'\] double_pedal: expected true or false"),
        ('name = "snare"', "name = 5", r"\[piece #2\] name: expected a string \(got 5\)"),
        ('name = "snare"', 'name = " "', r"\[piece ' '\] name: a piece needs a name"),
        ("[kit]", 'kit = "x"\n[kit2]', r"\[kit\]: expected a table, got str"),
    ],
)  # fmt: skip
def test_kit_wrong_types_are_named(tmp_path: Path, old: str, new: str, pattern: str) -> None:
    expect(KitError, load_kit, edited(tmp_path, KIT, old, new, "mine.toml"), pattern)


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        ("seat_height_m = 0.52", "seat_height_m = 0.52\ncolour = 3", r"\[kit\] colour: unknown key"),
        ("radius_m = 0.178", "radius_m = 0.178\nweight_kg = 3", r"\[piece 'snare'\] weight_kg: unknown key"),
        ("tilt_deg = 8.0", "tilt_dgr = 8.0", r"\[piece 'snare'\] tilt_dgr: unknown key; did you mean 'tilt_deg'"),
        ("[kit]", "[stand]\nheight = 1\n\n[kit]", r"stand: unknown key"),
    ],
)  # fmt: skip
def test_kit_unknown_keys_are_named(tmp_path: Path, old: str, new: str, pattern: str) -> None:
    expect(KitError, load_kit, edited(tmp_path, KIT, old, new, "mine.toml"), pattern)


# ---- note maps: wrong types and unknown keys -------------------------------------------------

KICK_NOTE = '36 = { piece = "kick", zone = "head", label = "Kick" }'


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        (KICK_NOTE, '36 = "kick"', r"\[notes.36\]: expected a table, got str"),
        ("hihat_cc = 4", "hihat_cc = 4.5", r"\[map\] hihat_cc: expected an integer \(got 4.5\)"),
        ("hihat_cc = 4", 'hihat_cc = "4"', r"\[map\] hihat_cc: expected an integer \(got '4'\)"),
        ('label = "Kick"', "label = 5", r"\[notes.36\] label: expected a string \(got 5\)"),
        ("36 = { piece", '"x" = { piece', r"\[notes\] x: note keys must be MIDI note numbers"),
        ("hihat_cc_closed = 90", "hihat_cc_closed = 90\nhihat_cc_open = 0", r"\[map\] hihat_cc_open: unknown key"),
        ('label = "Kick"', 'label = "Kick", velocity = 3', r"\[notes.36\] velocity: unknown key"),
        ("[notes]", "notes = 5\n[other]", r"\[map\] notes: unknown key"),
    ],
)  # fmt: skip
def test_map_wrong_types_and_unknown_keys_are_named(
    tmp_path: Path, old: str, new: str, pattern: str
) -> None:
    expect(NoteMapError, load_note_map, edited(tmp_path, MAP, old, new, "roland-td.toml"), pattern)


# ---- pieces out of reach --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        (SNARE_AT, "position_m = [-0.07, 4.0, 0.64]", r"\[piece 'snare'\] position_m: is more than 3.0 m from the seat"),
        (SNARE_AT, "position_m = [-0.07, 0.36, -0.2]", r"\[piece 'snare'\] position_m: the playing surface's rim reaches 0.225 m below the floor"),
        ("position_m = [0.06, 0.58, 0.28]", "position_m = [0.06, 0.58, -0.28]", r"\[piece 'kick'\] position_m: .* 0.559 m below the floor"),
        (KICK_PEDAL_AT, "pedal_position_m = [0.10, 0.38, -0.3]", r"\[piece 'kick'\] pedal_position_m: is 0.300 m below the floor"),
    ],
)  # fmt: skip
def test_pieces_far_away_or_under_the_floor_are_refused_at_load(
    tmp_path: Path, old: str, new: str, pattern: str
) -> None:
    path = edited(tmp_path, KIT, old, new, "mine.toml")
    expect(KitError, load_kit, path, pattern)


def test_a_kick_resting_on_the_floor_is_accepted(tmp_path: Path) -> None:
    # rock5's kick head (radius 0.279 m, vertical) touches the floor at z = 0.001 m; one
    # centimetre lower still touches it, within the tolerance, and the rig still plays it.
    path = edited(
        tmp_path,
        KIT,
        "position_m = [0.06, 0.58, 0.28]",
        "position_m = [0.06, 0.58, 0.271]",
        "mine.toml",
    )
    rig = build_rig(load_kit(str(path)))
    assert rig.hand_ok.any()
    for name in ("rock5", "rock5-left"):
        build_rig(load_kit(name))  # the bundled kits are playable


def left_shoulder_shortfall(target: list[float]) -> float:
    """How far ``target`` lies beyond the left arm + stick, from the body's dimensions."""
    skel = build_skeleton(None, 0.52)
    _, wp = neutral_world(skel, SecondaryParams().lean_deg)
    return float(np.linalg.norm(np.array(target) - wp[0, J["l_shoulder"]])) - skel.arm_reach


@pytest.mark.parametrize(
    ("old", "new", "pattern"),
    [
        (SNARE_AT, "position_m = [-0.07, 2.0, 0.64]", r"piece 'snare' zone head is out of reach of the LH stick by (\d+) mm"),
        ("position_m = [0.62, 0.50, 1.02]", "position_m = [0.62, 0.50, 2.6]", r"piece 'ride' zone bow is out of reach of the RH stick by \d+ mm"),
        (KICK_PEDAL_AT, "pedal_position_m = [0.10, 1.5, 0.02]", r"pedal of 'kick' at \[0.1, 1.5, 0.02\] m is out of reach of the RF foot by \d+ mm"),
        ("position_m = [-0.12, 0.60, 0.84]", "position_m = [-1.9, 0.60, 0.84]", r"piece 'tom1' zone head is out of reach of the RH stick"),
    ],
)  # fmt: skip
def test_unreachable_pieces_name_piece_zone_limb_and_shortfall(
    tmp_path: Path, old: str, new: str, pattern: str
) -> None:
    path = edited(tmp_path, KIT, old, new, "mine.toml")
    kit = load_kit(str(path))  # the file itself is well formed: reach depends on the body
    with pytest.raises(UnreachableError, match=pattern) as err:
        build_rig(kit)
    message = str(err.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    if "'snare'" in message:  # the shortfall is the body's: shoulder to target minus the arm
        found = re.search(pattern, message)
        assert found is not None
        mm = int(found.group(1))
        expected = left_shoulder_shortfall([-0.07, 2.0, 0.64]) * 1000
        assert abs(mm - expected) < 10, (mm, expected)
