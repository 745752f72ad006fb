"""``--background``: a colour, an image, chroma green or transparent behind the stage.

Parsing is pure; the pixels come from a real EGL context (llvmpipe without a GPU); the alpha
videos are read back with PyAV, the independent reader (VP9's alpha plane only through the
``libvpx-vp9`` decoder: FFmpeg's own VP9 decoder drops it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import av
import mido
import numpy as np
import pytest

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.background import (
    CHROMA_GREEN,
    HALL,
    Background,
    BackgroundError,
    parse_background,
)
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import Camera, kit_cameras
from livedrummer.render.kitmesh import STAGE_RADIUS_M, build_kit_mesh
from services.bench._ports import free_port_base
from services.cli import main
from services.display.background import load_background
from services.display.context import DisplayError, headless_context
from services.display.png import write_png
from services.display.renderer import Renderer

W, H = 240, 136
KIT = load_kit("rock5")


def test_parse_colours_keywords_and_images() -> None:
    assert parse_background("#ff8000").rgb == (1.0, 128 / 255, 0.0)
    assert parse_background("#fff") == Background("colour", (1.0, 1.0, 1.0))
    assert parse_background("chroma").rgb == CHROMA_GREEN
    assert parse_background("Transparent").alpha == 0.0
    assert parse_background("hall") == Background()
    img = parse_background("stage.jpg")
    assert (img.kind, img.path, img.alpha) == ("image", "stage.jpg", 1.0)
    for bad in ("#12", "#gggggg", "#1234567", " "):
        with pytest.raises(BackgroundError, match="background"):
            parse_background(bad)


@pytest.fixture(scope="module")
def ctx() -> Any:
    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


@pytest.fixture(scope="module")
def body(tmp_path_factory: pytest.TempPathFactory) -> BodyScene:
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000, time=0)])
    for delta, note in [(0, 36), (240, 38), (240, 36)]:
        track.append(mido.Message("note_on", channel=9, note=note, velocity=100, time=delta))
    track.append(mido.Message("note_off", channel=9, note=36, velocity=0, time=240))
    mid.tracks.append(track)
    path = tmp_path_factory.mktemp("bg") / "g.mid"
    mid.save(path)
    note_map = load_note_map("general-midi")
    return BodyScene.perform(read_midi_file(path, note_map), KIT, note_map)


def disc(cam: Camera, scale: float = 1.0) -> np.ndarray:
    """Pixels (H, W) whose centre is inside the stage floor's disc ``scale`` times as large."""
    a = np.linspace(0, 2 * np.pi, 256, endpoint=False)
    r = scale * STAGE_RADIUS_M
    ring = np.c_[r * np.cos(a), r * np.sin(a), np.zeros_like(a)]
    centre = np.mean([p.position_m for p in KIT.pieces], axis=0)
    ring[:, :2] += [centre[0], centre[1] * 0.5]
    clip = np.c_[ring, np.ones(len(ring))] @ cam.view_projection(W / H).T.astype(np.float64)
    px = np.c_[(clip[:, 0] / clip[:, 3] + 1) / 2 * W, (1 - clip[:, 1] / clip[:, 3]) / 2 * H]
    ys, xs = np.mgrid[0:H, 0:W] + 0.5
    inside = np.zeros((H, W), bool)
    for i in range(len(px)):
        x0, y0 = px[i - 1]
        x1, y1 = px[i]
        crosses = (y0 > ys) != (y1 > ys)
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x0 + (ys - y0) * (x1 - x0) / (y1 - y0)
        inside ^= crosses & (xs < xi)
    return inside


def grown(mask: np.ndarray, px: int = 2) -> np.ndarray:
    """``mask`` grown by ``px`` pixels (no wrap-around at the frame's edges)."""
    padded = np.pad(mask, px)
    out = np.zeros_like(mask)
    for dy in range(2 * px + 1):
        for dx in range(2 * px + 1):
            out |= padded[dy : dy + mask.shape[0], dx : dx + mask.shape[1]]
    return out


def off_stage(cam: Camera) -> np.ndarray:
    """Pixels more than 2 px outside the stage floor's disc."""
    out: np.ndarray = ~grown(disc(cam))
    return out


def draw(ctx: Any, body: BodyScene | None, bg: Background, camera: str = "front") -> np.ndarray:
    r = Renderer(ctx, build_kit_mesh(KIT), BODY_SKELETON, (W, H), samples=0, background=bg)
    r.draw(None if body is None else body.frame_at(0.5), kit_cameras(KIT)[camera])
    return r.read_rgba_top()


def empty(ctx: Any, body: BodyScene | None) -> np.ndarray:
    """Pixels (H, W) where nothing is drawn: off the stage and showing the hall's colour."""
    hall = draw(ctx, body, Background())[..., :3]
    colour = np.round(np.array(HALL) * 255).astype(np.uint8)
    mask: np.ndarray = off_stage(kit_cameras(KIT)["front"]) & np.all(hall == colour, axis=-1)
    assert mask.sum() > 0.5 * off_stage(kit_cameras(KIT)["front"]).sum()
    return mask


def test_transparent_is_alpha_0_off_the_stage_and_opaque_on_the_drummer(
    ctx: Any, body: BodyScene
) -> None:
    bg = parse_background("transparent")
    with_body = draw(ctx, body, bg)
    without = draw(ctx, None, bg)
    outside = empty(ctx, body)
    assert outside.sum() > 0.05 * W * H
    assert np.all(with_body[outside, 3] == 0)
    drummer = np.abs(with_body[..., :3].astype(int) - without[..., :3].astype(int)).sum(-1) > 30
    assert drummer.sum() > 200  # the drummer is drawn ...
    assert np.all(with_body[drummer, 3] == 255)  # ... opaque
    stage = ~grown(~disc(kit_cameras(KIT)["front"], 0.8))  # well inside the fading rim
    assert stage.sum() > 0.2 * W * H
    assert np.all(without[stage, 3] == 255)  # the stage is there, fading only at its rim


def test_colour_and_chroma_fill_off_stage(ctx: Any) -> None:
    outside = empty(ctx, None)
    for spec, want in (("#336699", (0x33, 0x66, 0x99)), ("chroma", (0, 177, 64))):
        img = draw(ctx, None, parse_background(spec))
        assert np.all(img[outside, :3] == want), spec
        assert np.all(img[..., 3] == 255)


def test_an_image_is_stretched_behind_the_stage_top_row_up(ctx: Any, tmp_path: Path) -> None:
    picture = np.zeros((60, 80, 3), np.uint8)
    picture[:30] = (250, 40, 40)  # red top half
    picture[30:] = (40, 40, 250)  # blue bottom half
    path = tmp_path / "backdrop.png"
    write_png(path, picture)
    bg = load_background(str(path))
    assert bg.image is not None and bg.image.shape == (60, 80, 3)
    img = draw(ctx, None, bg)
    top = empty(ctx, None)
    top[H // 2 - 4 :] = False
    assert top.sum() > 100
    np.testing.assert_allclose(img[top, :3].mean(axis=0), (250, 40, 40), atol=3)
    assert np.all(img[..., 3] == 255)
    with pytest.raises(BackgroundError, match="nothere"):
        load_background(str(tmp_path / "nothere.png"))
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"not a picture")
    with pytest.raises(BackgroundError, match="broken"):
        load_background(str(broken))


@pytest.fixture(scope="module")
def midi(tmp_path_factory: pytest.TempPathFactory) -> Path:
    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack([mido.MetaMessage("set_tempo", tempo=500_000, time=0)])
    for delta, note in [(0, 36), (240, 38)]:
        track.append(mido.Message("note_on", channel=9, note=note, velocity=100, time=delta))
    track.append(mido.Message("note_off", channel=9, note=38, velocity=0, time=120))
    mid.tracks.append(track)
    path = tmp_path_factory.mktemp("bgcli") / "g.mid"
    mid.save(path)
    return path


def alpha_frames(path: Path) -> list[np.ndarray]:
    """Every frame's alpha plane, decoded by PyAV (libvpx-vp9 for VP9, as FFmpeg needs)."""
    out = []
    with av.open(str(path)) as c:
        stream = c.streams.video[0]
        if stream.codec_context.name == "vp9":
            dec = av.CodecContext.create("libvpx-vp9", "r")
            frames = [f for p in c.demux(stream) for f in dec.decode(p)]  # type: ignore[attr-defined]
        else:
            frames = list(c.decode(stream))
        for f in frames:
            assert "a" in f.format.name.replace("yuv", ""), f.format.name  # an alpha plane
            out.append(f.to_ndarray(format="rgba")[..., 3])
    return out


@pytest.mark.parametrize("suffix", [".mov", ".webm"])
def test_transparent_video_decodes_back_with_alpha(midi: Path, tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"show{suffix}"
    argv = [
        "render",
        str(midi),
        "--size",
        "160x90",
        "--fps",
        "10",
        "--tail",
        "0",
        "--camera",
        "front",
        "--background",
        "transparent",
        "-o",
        str(out),
    ]
    assert main(argv) == 0
    alphas = alpha_frames(out)
    assert len(alphas) >= 4
    for a in alphas:
        assert (a == 0).mean() > 0.2 and (a == 255).mean() > 0.2  # hall gone, stage there
    with av.open(str(out)) as c:
        assert c.streams.audio  # the drum track is in it


def test_transparent_pngs_and_bad_values(midi: Path, tmp_path: Path, capsys: Any) -> None:
    frames = tmp_path / "frames"
    argv = [
        "render",
        str(midi),
        "--size",
        "160x90",
        "--fps",
        "10",
        "--tail",
        "0",
        "--camera",
        "front",
        "--background",
        "transparent",
    ]
    assert main([*argv, "--frames-dir", str(frames)]) == 0
    first = sorted(frames.glob("*.png"))[0]
    with av.open(str(first)) as c:
        frame = next(c.decode(video=0))
    assert frame.format.name == "rgba"
    a = frame.to_ndarray(format="rgba")[..., 3]
    assert a.min() == 0 and a.max() == 255
    capsys.readouterr()
    bad = [
        ([*argv, "-o", str(tmp_path / "x.mp4")], ".mov (ProRes 4444) or .webm"),
        (["render", str(midi), "--background", "#12", "-o", str(tmp_path / "y.mp4")], "#12"),
        (["render", str(midi), "--background", str(tmp_path / "none.jpg")], "none.jpg"),
        (["display", str(midi), "--background", "transparent"], "a window shows no alpha"),
    ]
    for args, message in bad:
        assert main(args) == 2, args
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err


def test_the_live_headless_recording_has_the_background(tmp_path: Path) -> None:
    """``up --headless`` passes --background to its display: chroma green behind the stage."""
    import os
    import subprocess
    import sys

    base = free_port_base()
    frames = tmp_path / "frames"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    env.pop("DISPLAY", None)
    env.pop("WAYLAND_DISPLAY", None)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--demo",
            "--headless",
            "--port-base",
            str(base),
            "--seconds",
            "2",
            "--background",
            "chroma",
            "--frames-dir",
            str(frames),
            "--png",
            "--size",
            "160x90",
            "--fps",
            "10",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=Path(__file__).resolve().parents[3],
    )
    assert done.returncode == 0, done.stderr[-1500:]
    pngs = sorted(frames.glob("*.png"))
    assert pngs, done.stderr[-800:]
    with av.open(str(pngs[-1])) as c:
        img = next(iter(c.decode(video=0))).to_ndarray(format="rgb24").astype(int)
    corner = img[:8, :8].reshape(-1, 3).mean(axis=0)  # the sky above the stage
    assert corner[1] > 150 and corner[0] < 80 and corner[2] < 80, corner


def test_render_look_picks_the_show_lights(midi: Path, tmp_path: Path, capsys: Any) -> None:
    argv = [
        "render",
        str(midi),
        "--size",
        "160x90",
        "--fps",
        "10",
        "--end",
        "0.3",
        "--camera",
        "front",
    ]
    shown = {}
    for look in ("concert", "neon"):
        frames = tmp_path / look
        assert main([*argv, "--look", look, "--frames-dir", str(frames)]) == 0
        assert f"look {look}" in capsys.readouterr().out
        with av.open(str(sorted(frames.glob("*.png"))[0])) as c:
            shown[look] = next(c.decode(video=0)).to_ndarray(format="rgb24").astype(int)
    # neon's magenta and cyan wash against concert's warm key: the kit is coloured otherwise
    assert np.abs(shown["neon"] - shown["concert"]).mean() > 3
    with pytest.raises(SystemExit) as bad:
        main([*argv, "--look", "disco"])
    assert bad.value.code == 2 and "--look" in capsys.readouterr().err
