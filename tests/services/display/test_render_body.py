"""The body model drawn by the renderer (EGL, llvmpipe without a GPU): contact frames and joints.

A short General MIDI groove is animated by the real body (optimal sticking) on the bundled kit
and on its mirror; in the contact frame of a snare onset the snare lights up and the playing
stick's tip lands on the snare head in the picture; the drummer is drawn where the body puts
the joints. Small frames (320x180) keep it fast.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mido
import numpy as np
import pytest

from livedrummer.body.skeleton import J
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, kit_cameras
from livedrummer.render.kitmesh import basis, build_kit_mesh
from livedrummer.render.scene import CH_HIGHLIGHT, SceneFrame, empty_channels
from services.display.context import DisplayError, headless_context
from services.display.renderer import Renderer

W, H = 320, 180
# General MIDI at 120 bpm, 480 ticks per beat: kick, hi-hat, snare + hi-hat, hi-hat, kick...
NOTES = [
    (0, 36),
    (0, 42),
    (240, 42),
    (240, 38),
    (0, 42),
    (240, 42),
    (240, 36),
    (0, 42),
    (240, 38),
    (0, 42),
    (480, 49),
]


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def groove(tmp_path_factory: pytest.TempPathFactory) -> Path:
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000, time=0)])
    track.append(mido.Message("note_on", channel=9, note=42, velocity=1, time=480))  # lead-in
    for delta, note in NOTES:
        track.append(mido.Message("note_on", channel=9, note=note, velocity=110, time=delta))
    track.append(mido.Message("note_off", channel=9, note=49, velocity=0, time=240))
    mid.tracks.append(track)
    path = tmp_path_factory.mktemp("body") / "groove.mid"
    mid.save(path)
    return path


def performed(groove: Path, kit: Kit) -> BodyScene:
    note_map = load_note_map("general-midi")
    return BodyScene.perform(read_midi_file(groove, note_map), kit, note_map)


def project(cam: Camera, points: np.ndarray) -> np.ndarray:
    """World points (N, 3) to pixel (x right, y down) coordinates (N, 2)."""
    clip = np.c_[points, np.ones(len(points))] @ cam.view_projection(W / H).T.astype(np.float64)
    ndc = clip[:, :2] / clip[:, 3:4]
    out: np.ndarray = np.c_[(ndc[:, 0] + 1) / 2 * W, (1 - ndc[:, 1]) / 2 * H]
    return out


def ring(centre: np.ndarray, normal: np.ndarray, radius: float, n: int = 64) -> np.ndarray:
    rot = basis(normal)
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    out: np.ndarray = centre + radius * (
        np.cos(a)[:, None] * rot[:, 0] + np.sin(a)[:, None] * rot[:, 1]
    )
    return out


def inside(poly: np.ndarray, x: float, y: float) -> bool:
    """Even-odd point-in-polygon."""
    result = False
    for i in range(len(poly)):
        (x0, y0), (x1, y1) = poly[i - 1], poly[i]
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            result = not result
    return result


def empty_kit(pieces: int, channels: np.ndarray | None = None) -> SceneFrame:
    away = np.zeros((2, 2, 3), np.float32)
    away[..., 2] = -1.0  # below the stage floor: hidden
    ch = empty_channels(pieces) if channels is None else channels
    return SceneFrame(np.zeros((0, 3), np.float32), away, ch)


@pytest.mark.parametrize("kit_name", ["rock5", "rock5-left"])
def test_snare_contact_frame_lights_the_snare_under_the_stick_tip(
    ctx: Any, groove: Path, kit_name: str
) -> None:
    kit = load_kit(kit_name)
    body = performed(groove, kit)
    st = body.performed.sticking
    snare = kit.pieces.index(kit.piece("snare"))
    hits = np.flatnonzero((st.piece == snare) & (st.limb >= 0))
    assert hits.size == 2
    t = float(st.onsets["time_s"][hits[0]])
    stick = int(st.limb[hits[0]])  # 0 right hand, 1 left hand
    assert stick in (0, 1)
    frame = body.frame_at(t)
    # The frame is the body's: joints are its world positions, the stick ends at its tip.
    _, _, _, wp = body.performed.animation.solve(np.array([t]))
    np.testing.assert_allclose(frame.joints_m, wp[0], atol=1e-5)
    tip = frame.sticks_m[stick, 1].astype(np.float64)
    np.testing.assert_allclose(tip, wp[0, J["r_tip" if stick == 0 else "l_tip"]], atol=1e-5)
    assert frame.channels[snare, CH_HIGHLIGHT] > 0.8

    cam = kit_cameras(kit)["overhead"]
    # no shadows: the hi-hat's shadow would dim the head this test sees light up
    r = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, (W, H), shadows=False)
    r.draw(empty_kit(len(kit.pieces)), cam)
    dark = r.read_rgb().astype(int)
    r.draw(empty_kit(len(kit.pieces), frame.channels), cam)
    lit = r.read_rgb().astype(int)
    r.draw(frame, cam)
    img = r.read_rgb().astype(int)

    piece = kit.piece("snare")
    centre = np.array(piece.position_m)
    # The snare head lights up: most points halfway out on the head are much brighter.
    half = project(cam, ring(centre, piece.normal, 0.5 * piece.radius_m, 16)).astype(int)
    gain = [lit[y, x].sum() - dark[y, x].sum() for x, y in half]
    assert np.median(gain) > 150
    # The playing stick's tip is over the snare head in the picture ...
    head = project(cam, ring(centre, piece.normal, piece.radius_m))
    tx, ty = project(cam, tip[None])[0]
    assert inside(head, tx, ty)
    # ... and drawn there: just behind the tip the pixel is the stick's wood, not the head.
    butt = frame.sticks_m[stick, 0].astype(np.float64)
    near_tip = tip + 0.02 * (butt - tip) / np.linalg.norm(butt - tip)
    x, y = project(cam, near_tip[None])[0].astype(int)
    assert np.abs(img[y, x] - lit[y, x]).sum() > 60
    assert img[y, x, 0] > img[y, x, 2] + 40  # warm wood, not the white highlighted head


def test_the_drummer_is_drawn_where_the_body_puts_him(ctx: Any, groove: Path) -> None:
    kit = load_kit("rock5")
    body = performed(groove, kit)
    frame = body.frame_at(1.25)
    cam = kit_cameras(kit)["front"]
    r = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, (W, H))
    r.draw(frame, cam)
    img = r.read_rgb().astype(int)
    r.draw(empty_kit(len(kit.pieces), frame.channels), cam)
    empty = r.read_rgb().astype(int)
    for joint in ("head_top", "r_shoulder", "l_shoulder"):
        x, y = project(cam, frame.joints_m[[J[joint]]].astype(np.float64))[0].astype(int)
        assert np.abs(img[y, x] - empty[y, x]).sum() > 60, joint
    # Moving the pose moves the drawing: the body raised 20 cm is drawn higher.
    raised = frame.joints_m.copy()
    raised[:, 2] += 0.2
    r.draw(SceneFrame(raised, frame.sticks_m, frame.channels), cam)
    up = r.read_rgb().astype(int)
    x, y = project(cam, frame.joints_m[[J["head_top"]]].astype(np.float64))[0].astype(int)
    x2, y2 = project(cam, raised[[J["head_top"]]].astype(np.float64))[0].astype(int)
    assert y2 < y
    assert np.abs(up[y2, x2] - empty[y2, x2]).sum() > 40
    assert up[y2, x2, 0] > up[y2, x2, 2]  # hair or skin, not the blue-black background


def test_hands_hold_the_sticks_in_every_frame(groove: Path) -> None:
    body = performed(groove, load_kit("rock5"))
    joints, sticks, _ = body.arrays(np.arange(0.0, 3.5, 1 / 30))
    for k, side in enumerate("rl"):
        grip = joints[:, J[f"{side}_stick"]]
        butt, tip = sticks[:, k, 0], sticks[:, k, 1]
        # the grip lies on the stick segment, between butt and tip
        d = np.linalg.norm(np.cross(tip - butt, grip - butt), axis=1) / np.linalg.norm(
            tip - butt, axis=1
        )
        assert d.max() < 1e-4
