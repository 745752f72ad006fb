"""A stage's drummers as space: footprints, spacing, the group camera, floor cells and spans.

Pure layout first (no OpenGL), then through real parts: the floor of a stage render against a
single drummer's (headless EGL), ``render --stage --end`` and a formation too tight for its kits
as one line and exit status 2 through the CLI.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from livedrummer.kit.loader import load_kit
from livedrummer.render.camera import pick_camera
from livedrummer.stage.formation import Formation, Placement, place
from livedrummer.stage.layout import (
    FILL,
    check_footprints,
    fit_group_camera,
    footprint,
    group_points,
    to_local,
    to_world,
)
from services.cli import main

GROOVE = Path(__file__).resolve().parents[3] / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


def test_the_footprint_holds_every_piece_and_the_drummer() -> None:
    kit = load_kit("rock5")
    f = footprint(kit)
    pts = np.array([p.position_m for p in kit.pieces])
    assert np.all(pts[:, 0] >= f.lo[0]) and np.all(pts[:, 0] <= f.hi[0])
    assert np.all(pts[:, 1] >= f.lo[1]) and np.all(pts[:, 1] <= f.hi[1])
    assert f.hi[2] > kit.seat_height_m + 0.8  # up to the head
    assert 1.5 < f.diameter_m < 2.6, f  # a five-piece kit is about 2 m across


def test_placement_frames_round_trip() -> None:
    p = Placement(3.0, -1.5, 37.0)
    pts = np.array([[0.2, 0.7, 1.0], [-1.0, 0.0, 0.0]])
    assert np.allclose(to_local(p, to_world(p, pts)), pts)
    assert np.allclose(to_world(p, np.zeros(2)), [3.0, -1.5])
    facing = to_world(p, np.array([0.0, 1.0])) - to_world(p, np.zeros(2))
    assert np.allclose(facing, [-math.sin(math.radians(37)), math.cos(math.radians(37))])


def test_an_arc_keeps_its_neighbours_spacing_apart() -> None:
    spots = place(Formation("arc", spacing=3.0), 12)  # 4 performers x 3 copies
    gaps = [math.hypot(a.x - b.x, a.y - b.y) for a, b in itertools.pairwise(spots)]
    assert min(gaps) >= 3.0 - 1e-6, gaps
    wide = place(Formation("arc", spacing=1.0, radius=6.0), 4)  # already wider: radius kept
    assert math.hypot(wide[0].x - wide[1].x, wide[0].y - wide[1].y) > 4.0


def test_kits_closer_than_a_footprint_are_named() -> None:
    f = footprint(load_kit("rock5"))
    ok = place(Formation("line", spacing=f.diameter_m + 0.01), 3)
    check_footprints(ok, [f] * 3, ["a", "b", "c"])
    tight = place(Formation("line", spacing=f.diameter_m - 0.2), 3)
    with pytest.raises(ValueError, match="drummers a and b stand"):
        check_footprints(tight, [f] * 3, ["a", "b", "c"])
    # a turned kit's footprint turns with it: two kits back to back overlap
    with pytest.raises(ValueError, match="need"):
        check_footprints([Placement(0, 0, 0), Placement(0, 1.0, 180)], [f] * 2, ["x", "y"])


@pytest.mark.parametrize("camera", ["stage", "front"])
def test_the_group_camera_centres_the_group_and_fills_the_frame(camera: str) -> None:
    kit = load_kit("rock5")
    spots = place(Formation("arc", spacing=3.0), 6)
    pts = group_points(spots, [footprint(kit)] * len(spots))
    aspect = 16 / 9
    cam = fit_group_camera(pick_camera(kit, camera), pts, aspect, "group")
    clip = np.c_[pts, np.ones(len(pts))] @ cam.view_projection(aspect).T.astype(float)
    ndc = clip[:, :2] / clip[:, 3:4]
    assert np.all(clip[:, 3] > 0)  # all in front of the eye
    lo, hi = ndc.min(axis=0), ndc.max(axis=0)
    assert np.allclose((lo + hi) / 2, 0.0, atol=0.02), (lo, hi)  # centred both ways
    assert max(hi - lo) / 2 == pytest.approx(FILL, abs=0.02)  # fills its binding side
    assert np.all(np.abs(ndc) <= 1.0)  # nothing cut


def _floor_roughness(rgba: np.ndarray, floor: np.ndarray) -> float:
    """The share of floor pixels whose luma jumps from a neighbour's by more than 0.1: jagged
    patches are many such jumps, planks and soft pools few."""
    luma = rgba[..., :3].astype(float) @ np.array([0.2126, 0.7152, 0.0722]) / 255.0
    jump = np.zeros_like(luma, bool)
    jump[:, 1:] |= np.abs(np.diff(luma, axis=1)) > 0.1
    jump[1:, :] |= np.abs(np.diff(luma, axis=0)) > 0.1
    inner = floor.copy()
    inner[1:, :] &= floor[:-1, :]
    inner[:, 1:] &= floor[:, :-1]
    return float(jump[inner].mean())


def _floor_mask(depth: np.ndarray, view_proj: np.ndarray) -> np.ndarray:
    """Pixels (bottom row first) whose nearest surface is the floor plane (|z| < 4 mm)."""
    h, w = depth.shape
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = (np.arange(h) + 0.5) / h * 2 - 1
    xx, yy = np.meshgrid(x, y)
    ndc = np.stack([xx, yy, depth * 2 - 1, np.ones_like(xx)], axis=-1)
    world = ndc @ np.linalg.inv(view_proj.astype(float)).T
    z = world[..., 2] / world[..., 3]
    mask: np.ndarray = (depth < 1.0) & (np.abs(z) < 0.004)
    return mask


@pytest.mark.usefixtures("gl_ok")
def test_a_stage_floor_is_as_smooth_as_one_drummers(tmp_path: Path) -> None:
    """Three drummers a footprint apart, their floor discs overlapping: the floor between them
    is as free of jumps as a single drummer's (before floor cells: blocky black patches where
    coplanar discs fought for pixels)."""
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
    from livedrummer.render.kitmesh import build_kit_mesh
    from services.cli.files import DEMO_MAP
    from services.display.context import headless_context
    from services.display.renderer import Renderer
    from services.display.stage_export import StageDrummer, StagePainter

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    perf = read_midi_file(GROOVE, note_map)
    body = BodyScene.perform(perf, kit, note_map)
    frame = next(iter(body.frames(np.array([4.0]))))
    spots = place(Formation("line", spacing=footprint(kit).diameter_m + 0.05), 3)
    size = (480, 270)
    ctx = headless_context()
    try:
        drummers = [StageDrummer(body, perf, s) for s in spots]
        painter = StagePainter(ctx, drummers, size, "stage")
        painter.draw([frame] * 3)
        stage = painter.read_rgba()
        stage_depth = np.frombuffer(
            painter.target.read(components=1, attachment=-1, dtype="f4"), np.float32
        ).reshape(size[1], size[0])
        stage_floor = _floor_mask(stage_depth, painter.camera.view_projection(size[0] / size[1]))
        one = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0)
        cam = pick_camera(kit, "stage")
        one.draw(frame, cam)
        single = one.read_rgba()
        single_depth = np.frombuffer(
            one._fbo.read(components=1, attachment=-1, dtype="f4"), np.float32
        ).reshape(size[1], size[0])
        single_floor = _floor_mask(single_depth, cam.view_projection(size[0] / size[1]))
    finally:
        ctx.release()
    assert stage_floor.mean() > 0.1 and single_floor.mean() > 0.1  # floor seen in both
    rough_stage = _floor_roughness(stage, stage_floor)
    rough_single = _floor_roughness(single, single_floor)
    assert rough_stage <= 1.5 * rough_single + 0.004, (rough_stage, rough_single)


def test_render_stage_honours_end_and_tail(tmp_path: Path) -> None:
    stage = tmp_path / "trio.toml"
    stage.write_text(
        f'[formation]\nshape = "line"\n\n[[performer]]\nid = "a"\nfile = "{GROOVE}"\n'
        'map = "roland-td"\n\n[ensemble]\ncopies = 2\n'
    )
    frames = tmp_path / "frames"
    assert (
        main(
            [
                "render",
                "--stage",
                str(stage),
                "--frames-dir",
                str(frames),
                "--size",
                "64x36",
                "--fps",
                "5",
                "--end",
                "2",
            ]
        )
        == 0
    )
    assert len(list(frames.glob("*.png"))) == 10  # 2 s at 5 fps, not the whole 14 s
    late = tmp_path / "late"
    assert (
        main(
            [
                "render",
                "--stage",
                str(stage),
                "--frames-dir",
                str(late),
                "--size",
                "64x36",
                "--fps",
                "5",
                "--start",
                "bar8",
                "--tail",
                "0.4",
            ]
        )
        == 0
    )
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    perf = read_midi_file(GROOVE, load_note_map("roland-td"))
    seconds = perf.duration_s + 0.4 - perf.grid.bar_start_s(7)
    assert len(list(late.glob("*.png"))) == math.ceil(seconds * 5 - 1e-9)
    # the same span as the single-drummer render of the same part with the same options
    for span, got in ((["--end", "2"], frames), (["--start", "bar8", "--tail", "0.4"], late)):
        single = tmp_path / f"single{len(span)}"
        assert (
            main(
                [
                    "render",
                    str(GROOVE),
                    "--map",
                    "roland-td",
                    "--frames-dir",
                    str(single),
                    "--size",
                    "64x36",
                    "--fps",
                    "5",
                    *span,
                ]
            )
            == 0
        )
        assert len(list(single.glob("*.png"))) == len(list(got.glob("*.png"))), span


def test_a_formation_too_tight_for_its_kits_is_one_line(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    stage = tmp_path / "tight.toml"
    stage.write_text(
        f'[formation]\nshape = "line"\nspacing = 1.2\n\n[[performer]]\nid = "a"\n'
        f'file = "{GROOVE}"\n\n[ensemble]\ncopies = 3\n'
    )
    for command in (
        ["render", "--stage", str(stage), "--frames-dir", str(tmp_path / "f")],
        ["check", "--stage", str(stage)],
    ):
        assert main(command) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1, err
        assert str(stage) in err and "a and a#2 stand 1.20 m apart" in err, err
    assert not (tmp_path / "f").exists()
