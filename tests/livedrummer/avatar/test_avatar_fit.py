"""``--fit``: an avatar of any size onto the default kit, by scaling it or moving the kit.

The avatars are the box-limbed humanoids of :mod:`tests.avatar_files`, written at the heights
asked for (one table scaled), so an avatar scaled by the ratio of two heights must be the file
of the other height.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import avatar_files as af
import numpy as np
import pytest

from livedrummer.avatar import fit
from livedrummer.avatar.loader import load_avatar_file
from livedrummer.avatar.model import Avatar
from livedrummer.body.check import check
from livedrummer.body.perform import perform
from livedrummer.body.skeleton import J
from livedrummer.errors import UnreachableError
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file


def _avatar(tmp: Path, height: float) -> Avatar:
    path = af.write(tmp, f"a{height}.vrm", af.Spec(height_m=height, pose="A", vrm="1"))
    return load_avatar_file(path)


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Avatar:
    return _avatar(tmp_path_factory.mktemp("fit"), 0.66)


def test_the_cli_knows_the_same_fits() -> None:
    from services.cli.performer import FITS

    assert fit.FITS == FITS


def test_a_scaled_avatar_is_the_avatar_of_that_height(small: Avatar, tmp_path: Path) -> None:
    tall = _avatar(tmp_path, 1.75)
    scaled = fit.scaled_avatar(small, 1.75 / 0.66)
    np.testing.assert_allclose(scaled.mesh.positions, tall.mesh.positions, atol=1e-5)
    # the loader floors hip_forward at 5 mm (both files have less), so the hips differ by it
    hips = [J["r_hip"], J["l_hip"]]
    np.testing.assert_allclose(
        np.delete(scaled.mesh.bind, hips, 0), np.delete(tall.mesh.bind, hips, 0), atol=1e-5
    )
    for f in dataclasses.fields(scaled.lengths):
        if f.name == "hip_forward":
            continue
        assert getattr(scaled.lengths, f.name) == pytest.approx(
            getattr(tall.lengths, f.name), abs=1e-4
        ), f.name
    assert scaled.lengths.stick == small.lengths.stick == 0.30  # a prop keeps its size
    assert fit.height_m(scaled) == pytest.approx(1.75, abs=1e-4)
    assert scaled.digest != small.digest  # a synth and a display can tell them apart


def test_auto_scales_a_small_avatar_to_the_kits_body(small: Avatar) -> None:
    kit = load_kit("rock5")
    with pytest.raises(UnreachableError):
        fit.fit_avatar(kit, small, "none")
    done = fit.fit_avatar(kit, small, "auto")
    assert done.mode == "avatar" and done.kit is kit and done.avatar is not None
    assert fit.reach_ratio(done.avatar.lengths) == pytest.approx(1.0, abs=0.05)
    assert done.scale == pytest.approx(1.0 / fit.reach_ratio(small.lengths), rel=0.2)
    assert "scaled x" in done.line and "does not reach the kit as it is" in done.line


def test_the_scaled_small_avatar_keeps_the_sticks_on_the_drums(
    small: Avatar, groove_dir: Path
) -> None:
    kit = load_kit("rock5")
    done = fit.fit_avatar(kit, small)
    note_map = load_note_map("roland-td")
    song = groove_dir / "drummer1/session1/1_funk_80_beat_4-4.mid"
    played = perform(read_midi_file(song, note_map), done.rig, note_map)
    r = check(played.animation, played.sticking, 100.0)
    assert r.not_played == 0
    assert float(np.max(r.contact_error_m)) <= 0.005 and r.penetration_m <= 0.002


def test_moving_the_kit_scales_throne_pieces_and_pedals(tmp_path: Path) -> None:
    kit = load_kit("rock5")
    near = _avatar(tmp_path, 1.45)  # reach x0.78: too short for the kit as it stands
    with pytest.raises(UnreachableError):
        fit.fit_avatar(kit, near, "none")
    done = fit.fit_avatar(kit, near, "kit")
    assert done.mode == "kit" and done.avatar is near
    k = done.scale
    assert k == pytest.approx(fit.reach_ratio(near.lengths), rel=0.2) and k < 1.0
    assert done.kit.seat_height_m == pytest.approx(kit.seat_height_m * k)
    for old, new in zip(kit.pieces, done.kit.pieces, strict=True):
        np.testing.assert_allclose(new.position_m, np.array(old.position_m) * k)
        assert new.radius_m == old.radius_m  # stands move, drums keep their size
        if old.pedal_position_m is not None:
            np.testing.assert_allclose(new.pedal_position_m, np.array(old.pedal_position_m) * k)
    assert "throne 0.52 -> " in done.line


def test_auto_leaves_an_avatar_that_reaches_alone_and_refuses_what_it_cannot(
    small: Avatar, tmp_path: Path
) -> None:
    kit = load_kit("rock5")
    own = _avatar(tmp_path, 1.80)
    done = fit.fit_avatar(kit, own, "auto")
    assert done.mode == "none" and done.avatar is own and done.kit is kit
    with pytest.raises(UnreachableError, match=r"reach is x0\.3\d .* beyond"):
        fit.fit_avatar(kit, small, "kit")  # a kit moved x0.35 would crowd its pieces
    with pytest.raises(UnreachableError, match=r"--fit none; --fit auto would fit it: avatar x"):
        fit.fit_avatar(kit, small, "none")
    assert fit.fit_avatar(kit, None).line.startswith("the built-in character")
