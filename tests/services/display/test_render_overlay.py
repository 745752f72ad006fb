"""The overlays: SMED's scrolling score and the joint-angle graph, models, pixels and GPU.

The models and the rasterizer are pure numpy and are tested on hand-made onsets and joint
arrays (and on the body at a known pose); the GPU tests read back a headless frame
(llvmpipe where there is no GPU) and prove the strips are blended into what export writes.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import av
import mido
import numpy as np
import pytest

from livedrummer.body import quat
from livedrummer.body.fk import forward
from livedrummer.body.skeleton import ARM, N_JOINTS, J, build_skeleton
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.midi.notemap import load_note_map
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.overlay import (
    ANGLE_NAMES,
    HISTORY_S,
    LOOKAHEAD_S,
    OVERLAYS,
    AngleModel,
    Lanes,
    OverlayError,
    OverlayModels,
    ScoreModel,
    joint_angles,
    parse_overlays,
)
from livedrummer.render.overlay_raster import (
    ANGLE_RGB,
    BACKGROUND,
    LIMB_RGB,
    NOW_LINE,
    AngleStrip,
    ScoreStrip,
    fill_boxes,
    marker_rgb,
    now_column,
    overlay_image,
)
from livedrummer.render.transport import KEYS
from livedrummer.sticking.result import NOT_PLAYED, Sticking
from livedrummer.timeline.events import ONSET_DTYPE
from services.cli import main
from services.display.context import headless_context
from services.display.renderer import Renderer
from services.display.window import OVERLAY_KEYS

RH, LH, RF, LF = 0, 1, 2, 3


@pytest.fixture(scope="module")
def kit() -> Kit:
    return load_kit("rock5")


def piece_of(kit: Kit, kind: PieceKind) -> int:
    return next(i for i, p in enumerate(kit.pieces) if p.kind is kind)


def sticking(kit: Kit, notes: list[tuple[float, int, int, int]]) -> Sticking:
    """A hand-made sticking from (time_s, piece, velocity, limb) rows."""
    onsets = np.zeros(len(notes), ONSET_DTYPE)
    onsets["time_s"] = [n[0] for n in notes]
    onsets["velocity"] = [n[2] for n in notes]
    return Sticking(
        onsets,
        np.array([n[3] for n in notes], np.int8),
        np.array([n[1] for n in notes], np.int16),
        {},
        "test",
        kit.name,
    )


# --- the score model -------------------------------------------------------------------------


def test_a_note_scrolls_from_the_right_edge_through_the_now_line_to_the_left_edge(kit: Kit) -> None:
    snare = piece_of(kit, PieceKind.SNARE)
    model = ScoreModel.from_sticking(sticking(kit, [(10.0, snare, 100, LH)]), kit)
    assert HISTORY_S == LOOKAHEAD_S == 4.0

    def xs(now: float) -> list[float]:
        return [float(x) for x in model.view(now).x]

    assert xs(10.0) == [pytest.approx(0.5)]  # at the now-line when it sounds
    assert xs(14.0) == [pytest.approx(0.0)]  # at the left edge 4 s later
    assert xs(6.0) == [pytest.approx(1.0)]  # enters at the right edge 4 s before
    assert xs(12.0) == [pytest.approx(0.25)]
    assert xs(14.001) == [] and xs(5.999) == []  # gone after, not yet before
    view = model.view(11.0)
    assert view.lane.tolist() == [model.lanes.lane_of_piece[snare]]
    assert view.limb.tolist() == [LH] and view.velocity.tolist() == [100]


def test_the_window_holds_exactly_the_notes_within_four_seconds(kit: Kit) -> None:
    rng = np.random.default_rng(3)
    times = np.sort(rng.uniform(0, 30, 400))
    pieces = rng.integers(0, len(kit.pieces), times.size)
    notes = [(float(t), int(p), 90, RH) for t, p in zip(times, pieces, strict=True)]
    model = ScoreModel.from_sticking(sticking(kit, notes), kit)
    for now in (0.0, 7.3, 15.0, 29.9):
        view = model.view(now)
        inside = times[(times >= now - 4.0) & (times <= now + 4.0)]
        assert view.x.size == inside.size
        np.testing.assert_allclose(view.x, 0.5 + (inside - now) / 8.0)
        np.testing.assert_array_equal(
            view.lane,
            model.lanes.lane_of_piece[pieces[(times >= now - 4.0) & (times <= now + 4.0)]],
        )


def test_lanes_run_like_a_drum_staff_cymbals_on_top_kick_at_the_bottom(kit: Kit) -> None:
    lanes = Lanes.from_kit(kit)
    assert lanes.count == len(kit.pieces)
    assert sorted(lanes.lane_of_piece.tolist()) == list(range(len(kit.pieces)))
    lane = {p.name: int(lanes.lane_of_piece[i]) for i, p in enumerate(kit.pieces)}
    assert max(lane["crash1"], lane["ride"], lane["splash"]) < lane["hihat"] < lane["snare"]
    assert lane["snare"] < lane["tom1"] < lane["tom2"] < lane["tom3"] < lane["kick"]
    assert lanes.labels[lane["tom2"]] == "T2" and lanes.labels[lane["kick"]] == "KK"
    grouped = Lanes.from_kit(kit, grouped=True)
    assert grouped.labels == ("CY", "HH", "SN", "TM", "KK")
    assert grouped.lane_of_piece[piece_of(kit, PieceKind.RIDE)] == 0
    assert grouped.lane_of_piece[piece_of(kit, PieceKind.TOM)] == 3


def test_onsets_without_a_piece_are_counted_not_drawn(kit: Kit) -> None:
    snare = piece_of(kit, PieceKind.SNARE)
    st = sticking(kit, [(1.0, snare, 80, RH), (1.5, -1, 80, NOT_PLAYED), (2.0, snare, 80, LH)])
    model = ScoreModel.from_sticking(st, kit)
    assert model.unplaced == 1
    assert model.time_s.tolist() == [1.0, 2.0]


def test_marker_colour_is_the_limbs_and_soft_notes_are_darker() -> None:
    full = marker_rgb(np.array([RH, LH, RF, LF, NOT_PLAYED]), np.full(5, 127))
    np.testing.assert_array_equal(full, LIMB_RGB)
    assert len({tuple(c) for c in LIMB_RGB}) == 5  # every limb its own colour
    soft = marker_rgb(np.array([RH]), np.array([20]))
    assert (soft[0] < LIMB_RGB[0]).all()


def test_overlay_names_parse_and_a_typo_names_itself() -> None:
    assert parse_overlays("score,joints") == {"score", "joints"}
    assert parse_overlays(" joints ") == {"joints"}
    assert parse_overlays("") == frozenset() == parse_overlays("none")
    with pytest.raises(OverlayError, match="'scroe'"):
        parse_overlays("scroe,joints")


# --- joint angles ----------------------------------------------------------------------------


def arm_pose(
    shoulder_dir: tuple[float, ...], fore_dir: tuple[float, ...], stick_dir: tuple[float, ...]
) -> np.ndarray:
    """(24, 3) joints: a vertical spine and the right arm built from segment directions."""
    p = np.zeros((N_JOINTS, 3))
    p[J["lower_back"]] = (0.0, 0.0, 0.7)
    p[J["chest"]] = (0.0, 0.0, 1.0)
    sh, el, wr, st, tip = ARM["R"]
    p[sh] = (0.2, 0.0, 1.2)
    p[el] = p[sh] + 0.3 * np.asarray(shoulder_dir) / np.linalg.norm(shoulder_dir)
    p[wr] = p[el] + 0.27 * np.asarray(fore_dir) / np.linalg.norm(fore_dir)
    p[st] = p[wr] + 0.08 * np.asarray(fore_dir) / np.linalg.norm(fore_dir)
    p[tip] = p[st] + 0.3 * np.asarray(stick_dir) / np.linalg.norm(stick_dir)
    for j in ARM["L"]:  # the left arm hangs straight
        p[j] = p[J["chest"]] + (-0.2, 0.0, 0.2 - 0.25 * ARM["L"].index(j))
    return p


def test_angles_of_hand_made_arms() -> None:
    down, fwd, side = (0, 0, -1), (0, 1, 0), (1, 0, 0)
    straight = joint_angles(arm_pose(down, down, down))
    np.testing.assert_allclose(straight, 0.0, atol=1e-6)  # flexion: straight is 0
    bent = joint_angles(arm_pose(down, fwd, fwd))
    assert bent[1] == pytest.approx(90.0) and bent[0] == pytest.approx(0.0)
    assert bent[2] == pytest.approx(0.0)
    raised = joint_angles(arm_pose(fwd, fwd, side))  # arm forward, stick across
    assert raised[0] == pytest.approx(90.0)
    assert raised[1] == pytest.approx(0.0, abs=1e-6) and raised[2] == pytest.approx(90.0)
    half = joint_angles(arm_pose(down, (0, 1, -1), (0, 1, 0)))
    assert half[1] == pytest.approx(45.0) and half[2] == pytest.approx(45.0)
    assert ANGLE_NAMES.index("r_elbow") == 1


def test_angles_follow_the_spine_not_the_world() -> None:
    p = arm_pose((0, 0, -1), (0, 0, -1), (0, 0, -1))
    p[J["lower_back"]] = p[J["chest"]] + (0.0, 0.3, 0.0)  # spine lying along y
    assert joint_angles(p)[0] == pytest.approx(90.0)


def test_angles_of_the_body_at_known_poses() -> None:
    skeleton = build_skeleton()
    local = quat.identity((2, N_JOINTS))
    # rest pose: arms hanging, sticks in line -> all zero; second sample: right elbow bent 90 deg
    local[1, J["r_elbow"]] = quat.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2)
    _, world = forward(skeleton, local, np.zeros((2, 3)))
    angles = joint_angles(world)
    np.testing.assert_allclose(angles[0], 0.0, atol=1e-5)
    np.testing.assert_allclose(angles[1], [0.0, 90.0, 0.0, 0.0, 0.0, 0.0], atol=1e-5)


def test_the_angle_model_samples_the_body(kit: Kit, groove: Path) -> None:
    from livedrummer.midi.smf import read_midi_file

    nm = load_note_map("general-midi")
    body = BodyScene.perform(read_midi_file(groove, nm), kit, nm)
    model = AngleModel.from_body(body, 2.0, chunk=50)  # several chunks
    assert model.degrees.shape == (121, 6)
    t = np.array([0.5, 1.25])
    np.testing.assert_allclose(
        model.degrees[(t * 60).astype(int)], joint_angles(body.arrays(t)[0]), atol=1e-3
    )
    assert model.degrees[:, 1].max() - model.degrees[:, 1].min() > 5  # the elbows move
    view = model.view(1.0)
    np.testing.assert_allclose(view.x[view.x.size // 2], 0.5, atol=1 / 480)
    assert view.x[0] <= 0.5 - 1.0 / 8.0 + 1e-9  # back to t = 0, the first sample
    assert view.degrees.shape == (view.x.size, 6)


# --- the rasterizer --------------------------------------------------------------------------


def test_score_pixels_markers_background_and_now_line(kit: Kit) -> None:
    snare, kick = piece_of(kit, PieceKind.SNARE), piece_of(kit, PieceKind.KICK)
    model = ScoreModel.from_sticking(
        sticking(kit, [(1.0, snare, 127, RH), (5.0, kick, 127, RF)]), kit
    )
    strip = ScoreStrip(model, 640, 120)
    img = np.zeros((120, 640, 4), np.uint8)
    strip.paint(img, 3.0)
    lane = model.lanes.lane_of_piece
    row = int(strip.lane_centre[lane[snare]])
    col = round(0.25 * 640)  # 2 s ago: a quarter of the way across
    np.testing.assert_array_equal(img[row, col], [*LIMB_RGB[RH], 255])
    krow, kcol = int(strip.lane_centre[lane[kick]]), round(0.75 * 640)
    np.testing.assert_array_equal(img[krow, kcol], [*LIMB_RGB[RF], 255])
    # the kick is a foot: a diamond, so its bounding box's corner is not painted
    top, left, _, _, _, diamond = strip.markers(model.view(3.0))
    assert diamond.tolist() == [False, True]
    assert tuple(img[int(top[1]), int(left[1])]) != (*LIMB_RGB[RF], 255)
    assert tuple(img[int(top[0]), int(left[0])]) == (*LIMB_RGB[RH], 255)  # a rectangle's is
    # empty panel: the background's colour and alpha, between lanes, away from the notes
    gap = int((strip.lane_centre[0] + strip.lane_centre[1]) / 2)
    np.testing.assert_array_equal(img[gap, 400], BACKGROUND)
    assert img[gap, 400, 3] < 255
    # the now-line at the centre column below the legend row
    c = now_column(640)
    assert c == 320
    assert (img[strip.band_h :, c] == NOW_LINE).all()
    # after the snare has left the window, its pixels are background again
    strip.paint(img, 5.01)
    assert tuple(img[row, round((0.5 - 4.01 / 8) * 640)]) != (*LIMB_RGB[RH], 255)
    assert not (img[:, :, :3] == LIMB_RGB[RH]).all(axis=2)[strip.band_h :].any()


def test_graph_pixels_are_the_curves_colours_at_their_angles() -> None:
    deg = np.array([10.0, 40.0, 70.0, 100.0, 130.0, 160.0], np.float32)
    model = AngleModel(60.0, np.tile(deg, (601, 1)))  # 10 s of constant angles
    strip = AngleStrip(model, 400, 100)
    img = np.zeros((100, 400, 4), np.uint8)
    strip.paint(img, 2.0)  # the first 2 s of the window are before t = 0: no data there
    for k in range(6):
        r = int(np.round(strip.row(np.array([deg[k]])))[0])
        np.testing.assert_array_equal(img[r, 300], [*ANGLE_RGB[k], 255])
        assert tuple(img[r, 40]) != (*ANGLE_RGB[k], 255)  # t = -1.6 s: no curve
    assert (img[strip.band_h :, 200] == NOW_LINE).all()
    # a 90-degree step: the column where it happens is painted all the way up
    steps = np.zeros((601, 6), np.float32)
    steps[240:] = 90.0  # at t = 4 s, 1 s before now: x = 0.375, column 150
    strip = AngleStrip(AngleModel(60.0, steps), 400, 100)
    strip.paint(img, 5.0)
    lo, hi = int(strip.row(np.array([90.0]))[0]), int(strip.row(np.array([0.0]))[0])
    painted = (img[lo:hi, 145:155, :3] == ANGLE_RGB[5]).all(axis=2).any(axis=1)
    assert hi - lo > 30 and painted.all()


def test_fill_boxes_clips_and_later_boxes_cover_earlier() -> None:
    img = np.zeros((10, 10, 4), np.uint8)
    fill_boxes(
        img,
        np.array([-2, 5]),
        np.array([-2, 5]),
        np.array([5, 10]),
        np.array([5, 10]),
        np.array([[1, 1, 1, 1], [2, 2, 2, 2]], np.uint8),
    )
    assert (img[:3, :3] == 1).all() and img[3, 3, 0] == 0
    assert (img[5:, 5:] == 2).all()
    fill_boxes(
        img,
        np.array([0]),
        np.array([0]),
        np.array([5]),
        np.array([5]),
        np.array([9, 9, 9, 9], np.uint8),
        np.array([True]),
    )
    assert img[2, 2, 0] == 9 and img[0, 0, 0] == 1 and img[0, 2, 0] == 9  # diamond


def test_strips_stack_at_the_bottom_score_above_graph(kit: Kit, groove: Path) -> None:
    from livedrummer.midi.smf import read_midi_file

    nm = load_note_map("general-midi")
    body = BodyScene.perform(read_midi_file(groove, nm), kit, nm)
    models = OverlayModels(body, 3.0)
    both = overlay_image((1280, 720), frozenset({"score", "joints"}), models)
    assert (both.rect.x, both.rect.width) == (0, 1280)
    assert both.rect.y + both.rect.height == 720 and 150 <= both.rect.height <= 200
    assert [type(s).__name__ for s, _, _ in both.strips] == ["ScoreStrip", "AngleStrip"]
    assert both.paint(1.0).shape == (both.rect.height, 1280, 4)
    one = overlay_image((1280, 720), frozenset({"joints"}), models)
    assert one.rect.height < both.rect.height and one.rect.y + one.rect.height == 720
    assert overlay_image((1280, 720), frozenset(), models).empty


# --- on the GPU ------------------------------------------------------------------------------


@pytest.fixture
def groove(write_midi) -> Path:  # type: ignore[no-untyped-def]
    msgs: list[mido.Message] = [mido.MetaMessage("set_tempo", tempo=500_000, time=0)]
    for delta, note, vel in [
        (0, 36, 110),
        (240, 38, 100),
        (240, 42, 90),
        (240, 38, 127),
        (240, 36, 120),
        (240, 42, 70),
    ]:
        msgs.append(mido.Message("note_on", channel=9, note=note, velocity=vel, time=delta))
        msgs.append(mido.Message("note_off", channel=9, note=note, velocity=0, time=30))
    path: Path = write_midi(msgs)
    return path


def test_the_overlay_is_blended_into_the_read_back_frame(
    gl_ok: None, kit: Kit, groove: Path
) -> None:
    from livedrummer.midi.smf import read_midi_file

    nm = load_note_map("general-midi")
    body = BodyScene.perform(read_midi_file(groove, nm), kit, nm)
    size = (320, 180)
    strips = overlay_image(size, frozenset({"score", "joints"}), OverlayModels(body, 3.0))
    r = strips.rect
    ctx = headless_context()
    try:
        renderer = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0)
        cam, frame = pick_camera(kit, "front"), body.frame_at(1.0)
        renderer.draw(frame, cam)
        plain = renderer.read_rgb().astype(np.int64)
        renderer.draw(frame, cam)
        image = strips.paint(1.0)
        renderer.draw_overlay(image, (r.x, r.y, r.width, r.height))
        shown = renderer.read_rgb().astype(np.int64)
        i420 = renderer.read_i420()  # the export path sees it too
        with pytest.raises(ValueError, match="rectangle"):
            renderer.draw_overlay(image[:-1], (r.x, r.y, r.width, r.height))
    finally:
        ctx.release()
    np.testing.assert_array_equal(shown[: r.y], plain[: r.y])  # above the strips: untouched
    assert (shown[r.y :] != plain[r.y :]).any(axis=2).mean() > 0.5
    # opaque pixels are the image's own; the now-line sits at the centre column
    c = now_column(size[0])
    for strip, top, height in strips.strips:  # each strip's line, below its legend row
        line = shown[r.y + top + strip.band_h : r.y + top + height, c]
        assert len(line) > 10 and (line == NOW_LINE[:3]).all()
    score_band = strips.strips[0][0].band_h
    # translucent pixels are the blend of the panel over the frame
    a = image[..., 3:4].astype(np.float64) / 255.0
    expected = image[..., :3] * a + plain[r.y :] * (1.0 - a)
    assert np.abs(shown[r.y :] - expected).max() <= 2
    luma_now = i420[r.y + score_band + 2, c]
    assert 70 <= luma_now <= 100  # BT.709 luma of (255, 40, 40) in limited range: about 81


def test_render_command_draws_the_overlays(gl_ok: None, groove: Path, tmp_path: Path,  # type: ignore[no-untyped-def]
                                           capsys) -> None:  # fmt: skip
    def frame(argv: list[str], name: str) -> np.ndarray:
        out = tmp_path / name
        code = main(
            [
                "render",
                str(groove),
                "--frames-dir",
                str(out),
                "--size",
                "160x90",
                "--fps",
                "10",
                "--tail",
                "0",
                "--camera",
                "front",
                *argv,
            ]
        )
        assert code == 0
        with av.open(str(sorted(out.glob("*.png"))[8])) as c:
            img: np.ndarray = next(iter(c.decode(video=0))).to_ndarray(format="rgb24")
        return img.astype(np.int64)

    plain = frame([], "plain")
    both = frame(["--overlay", "score,joints"], "both")
    assert "overlay score,joints" in capsys.readouterr().out
    assert (both[:45] == plain[:45]).all()  # the top half is the scene alone
    assert np.abs(both[60:] - plain[60:]).sum(axis=2).mean() > 10
    col = both[-8:, now_column(160)]  # the now-line, in the graph below its legend: red
    assert ((col[:, 0] > 200) & (col[:, 1] < 90)).mean() > 0.8
    code = main(["render", str(groove), "--frames-dir", str(tmp_path / "x"), "--overlay", "graph"])
    assert code == 2
    assert "'graph'" in capsys.readouterr().err


def test_window_overlay_keys_are_free_and_name_each_overlay() -> None:
    assert sorted(OVERLAY_KEYS.values()) == sorted(OVERLAYS)
    for key in OVERLAY_KEYS:
        assert key not in KEYS and not key.isdigit() and key not in ("q", "f", "escape")


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_window_plays_with_overlays_under_xvfb(groove: Path) -> None:
    run = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x360x24",
            sys.executable,
            "-c",
            "import sys; from services.cli import main; sys.exit(main())",
            "-v",
            "display",
            str(groove),
            "--size",
            "640x360",
            "--aa",
            "0",
            "--overlay",
            "score,joints",
            "--seconds",
            "1.5",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    line = next(ln for ln in run.stderr.splitlines() if "window:" in ln)
    assert int(line.split("window:")[1].split()[0]) > 3  # frames drawn
