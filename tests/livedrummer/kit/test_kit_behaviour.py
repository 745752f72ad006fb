"""What a piece does when struck or pedalled: footboards under the feet, toms that shake,
cymbals that swing by size. Geometry is read from the kit mesh and the body (pure); one
frame is drawn in a real EGL context and the pedal's pixels checked."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mido
import numpy as np
import pytest

from livedrummer.body.channels import VibrationParams, kit_channels, piece_vibration
from livedrummer.body.ik import foot_pitch
from livedrummer.body.skeleton import LEG, J
from livedrummer.errors import LivedrummerError
from livedrummer.kit.behaviour import FOOTBOARD_HINGE_M, footboard_angle, swing_of
from livedrummer.kit.loader import load_kit, load_kit_file
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BodyScene
from livedrummer.render.camera import kit_cameras
from livedrummer.render.kitmesh import MOTION_PEDAL, build_kit_mesh
from livedrummer.render.scene import CH_PEDAL, CH_WOBBLE, SceneFrame, empty_channels
from services.display.context import DisplayError, headless_context
from services.display.renderer import Renderer

KIT = load_kit("rock5")
INDEX = {p.name: i for i, p in enumerate(KIT.pieces)}


def board_centres(channels: np.ndarray) -> dict[int, np.ndarray]:
    """World centre of each piece's footboard with ``channels`` applied."""
    mesh = build_kit_mesh(KIT)
    inst = mesh.instances(channels)
    rows = np.flatnonzero(mesh.motion == MOTION_PEDAL)
    return {int(mesh.piece[r]): inst[r, 12:15].astype(np.float64) for r in rows}


def test_footboard_turn_lifts_the_ball_of_the_foot_by_its_rise() -> None:
    rest = board_centres(empty_channels(len(KIT.pieces)))
    assert set(rest) == {INDEX["kick"], INDEX["hihat"]}
    for rise in (0.01, 0.035, 0.07):
        ch = empty_channels(len(KIT.pieces))
        ch[:, CH_PEDAL] = footboard_angle(np.array(rise))
        up = board_centres(ch)
        for k in rest:
            # the board's middle, under the ball of the foot, rises by the foot's rise
            assert up[k][2] - rest[k][2] == pytest.approx(rise, abs=1e-5)
            assert np.linalg.norm(up[k][:2] - rest[k][:2]) < rise  # turned, not slid
    assert abs(float(footboard_angle(np.array(0.0)))) <= 1e-9  # at rest within 1e-9 rad
    assert FOOTBOARD_HINGE_M > 0.07


def test_the_ankle_flexes_as_the_foot_lifts() -> None:
    # flat within 1e-9 rad at rest: the physics, not one CPU's rounding of arcsin(sin(x))
    assert abs(float(foot_pitch(np.array(0.0), 0.15))) <= 1e-9
    assert abs(float(foot_pitch(np.array(-0.01), 0.15))) <= 1e-9  # pressed into the board
    pitch = foot_pitch(np.array([0.02, 0.04, 0.07]), 0.15)
    assert np.all(np.diff(pitch) > 0) and np.degrees(pitch[-1]) > 15.0


@pytest.fixture(scope="module")
def groove(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Kicks, a tom and a crash, with the hi-hat pedal opening and closing (CC4)."""
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000, time=0)])
    track.append(mido.Message("control_change", channel=9, control=4, value=127, time=0))
    for delta, note in [(480, 36), (480, 36), (240, 48), (240, 49), (480, 36)]:
        track.append(mido.Message("note_on", channel=9, note=note, velocity=110, time=delta))
    track.append(mido.Message("control_change", channel=9, control=4, value=0, time=120))
    track.append(mido.Message("control_change", channel=9, control=4, value=127, time=480))
    track.append(mido.Message("note_off", channel=9, note=36, velocity=0, time=240))
    mid.tracks.append(track)
    path = tmp_path_factory.mktemp("behaviour") / "groove.mid"
    mid.save(path)
    return path


def test_boards_follow_the_feet_in_a_performance(groove: Path) -> None:
    note_map = load_note_map("general-midi")
    scene = BodyScene.perform(read_midi_file(groove, note_map), KIT, note_map)
    times = np.arange(0.5, 4.0, 1 / 60)
    joints, _, channels = scene.arrays(times)
    rest = board_centres(empty_channels(len(KIT.pieces)))
    for piece, side in (("kick", "R"), ("hihat", "L")):
        k = INDEX[piece]
        pedal = np.array(KIT.pieces[k].pedal_position_m)
        toe = joints[:, LEG[side][3]].astype(np.float64)
        ankle = joints[:, LEG[side][2]].astype(np.float64)
        knee = joints[:, LEG[side][1]].astype(np.float64)
        rise = toe[:, 2] - pedal[2]
        board = np.array([board_centres(c)[k][2] for c in channels[::6]]) - rest[k][2]
        on_board = rise[::6] < 0.07  # within the board's travel the ball stays on it
        assert on_board.sum() > 5
        np.testing.assert_allclose(board[on_board], rise[::6][on_board], atol=2e-3)
        assert board.max() > 0.02, piece  # the board moves
        # the ankle flexes: the foot's angle to the shin changes over the strokes
        foot = (toe - ankle) / np.linalg.norm(toe - ankle, axis=1, keepdims=True)
        shin = (ankle - knee) / np.linalg.norm(ankle - knee, axis=1, keepdims=True)
        flex = np.degrees(np.arccos(np.clip(np.sum(foot * shin, axis=1), -1, 1)))
        assert np.ptp(flex) > 10.0, piece
    # the struck tom shakes, and it settles
    toms = [INDEX[n] for n in ("tom1", "tom2", "tom3")]
    tom = channels[:, toms, CH_WOBBLE]
    assert np.abs(tom).max() > 0.005
    assert np.abs(tom[-20:]).max() < 1e-4
    assert J["r_toe"] == LEG["R"][3]


def test_toms_shake_small_and_fast_cymbals_swing_by_size() -> None:
    t = np.arange(0.0, 2.0, 0.001)
    hit = [np.array([0.0])]
    v = [np.array([1.0])]
    none = [np.zeros(0)]
    tom = KIT.piece("tom1")
    splash, crash, ride = KIT.piece("splash"), KIT.piece("crash2"), KIT.piece("ride")
    swing = {
        p.name: kit_channels((p,), t, hit, v, none, [None], np.zeros_like(t)).swing[:, 0]
        for p in (tom, splash, crash, ride)
    }

    def first_zero_s(x: np.ndarray) -> float:
        return float(t[1:][np.flatnonzero(np.diff(np.sign(x[1:])) != 0)[0] + 1])

    assert np.abs(swing["tom1"]).max() < 0.5 * np.abs(swing["crash2"]).max()
    assert np.abs(swing["tom1"][t > 0.5]).max() < 1e-3  # a shake is short
    assert first_zero_s(swing["tom1"]) < first_zero_s(swing["splash"])
    # a bigger cymbal swings slower and further
    assert first_zero_s(swing["splash"]) < first_zero_s(swing["crash2"])
    assert np.abs(swing["splash"]).max() < np.abs(swing["crash2"]).max()
    assert np.abs(swing["ride"]).max() < np.abs(swing["crash2"]).max()  # a ride is heavy
    # the 16" reference keeps the paper's swing
    sixteen = piece_vibration(KIT.piece("crash1"), VibrationParams())
    assert 2 * KIT.piece("crash1").radius_m == pytest.approx(16 * 0.0254, abs=0.001)
    assert sixteen.max_angle_rad == pytest.approx(VibrationParams().max_angle_rad, rel=0.01)
    assert swing_of(KIT.piece("kick")).max_angle_rad == 0.0


def _kit_file(tmp_path: Path, extra: str, kind: str = "crash") -> Path:
    src = Path(KIT.source).read_text() if KIT.source and Path(KIT.source).exists() else None
    assert src is not None
    marker = f'kind = "{kind}"\n'
    text = src.replace(marker, marker + extra, 1)
    path = tmp_path / "kit.toml"
    path.write_text(text)
    return path


def test_swing_deg_in_the_kit_file_sets_a_cymbals_swing(tmp_path: Path) -> None:
    kit = load_kit_file(_kit_file(tmp_path, "swing_deg = 3.0\n"))
    crash = next(p for p in kit.pieces if p.kind.value == "crash")
    assert crash.swing_deg == 3.0
    assert swing_of(crash).max_angle_rad == pytest.approx(np.radians(3.0))
    with pytest.raises(LivedrummerError, match="swing_deg"):
        load_kit_file(_kit_file(tmp_path, "swing_deg = 3.0\n", kind="tom"))
    with pytest.raises(LivedrummerError, match="swing_deg"):
        load_kit_file(_kit_file(tmp_path, "swing_deg = 90.0\n"))


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


def test_a_raised_footboard_is_drawn_raised(ctx: Any, tmp_path: Path) -> None:
    w, h = 320, 180
    cam = kit_cameras(KIT)["left"]
    r = Renderer(ctx, build_kit_mesh(KIT), None, (w, h), shadows=False)
    away = np.zeros((2, 2, 3), np.float32)
    away[..., 2] = -1.0
    empty = np.zeros((0, 3), np.float32)
    images = []
    for angle in (0.0, float(footboard_angle(np.array(0.07)))):
        ch = empty_channels(len(KIT.pieces))
        ch[INDEX["hihat"], CH_PEDAL] = angle
        r.draw(SceneFrame(empty, away, ch), cam)
        images.append(r.read_rgb().astype(int))
    changed = np.abs(images[1] - images[0]).sum(axis=2) > 30
    assert changed.sum() > 20
    # the change is where the hi-hat's footboard is drawn
    pedal = np.array(KIT.piece("hihat").pedal_position_m)
    clip = np.r_[pedal, 1.0] @ cam.view_projection(w / h).T.astype(np.float64)
    px = ((clip[0] / clip[3] + 1) / 2 * w, (1 - clip[1] / clip[3]) / 2 * h)
    ys, xs = np.nonzero(changed)
    assert abs(np.median(xs) - px[0]) < 40 and abs(np.median(ys) - px[1]) < 40
