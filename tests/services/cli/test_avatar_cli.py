"""``--avatar``, ``avatar info`` and ``avatars`` as a user meets them: real processes, real files.

``check --avatar`` on Groove MIDI Dataset files holds the stick tips on the drums (contact
within 5 mm, penetration within 2 mm) for every test avatar, on the default kit and its mirror,
because the rig is built from the avatar's own proportions.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import avatar_files as af
import pytest

SCRIPT = Path(sys.executable).parent / "livedrummer"
GROOVES = ("drummer1/session1/1_funk_80_beat_4-4.mid", "drummer6/session1/1_rock_70_beat_6-8.mid")


def run(*args: str, **env: str) -> subprocess.CompletedProcess[str]:
    command = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "services"]
    return subprocess.run(
        [*command, *args], capture_output=True, text=True, timeout=300, env={**os.environ, **env}
    )


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return af.write_all(tmp_path_factory.mktemp("avatars"))


@pytest.mark.parametrize("kit", ["rock5", "rock5-left"])
@pytest.mark.parametrize("name", list(af.AVATARS))
def test_check_keeps_the_sticks_on_the_drums(
    groove_dir: Path, files: dict[str, Path], name: str, kit: str
) -> None:
    grooves = [str(groove_dir / g) for g in GROOVES]
    proc = run(
        "check",
        *grooves,
        "--map",
        "roland-td",
        "--kit",
        kit,
        "--avatar",
        str(files[name]),
        "--json",
        "--summary",
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["avatar"] == str(files[name]) and out["files"] == 2
    assert out["notes"] > 500 and out["not_played"] == 0
    assert out["contact_error_mm"]["max"] <= 5.0
    assert out["penetration_mm"] <= 2.0


def test_bvh_export_has_the_avatars_proportions(
    groove_dir: Path, files: dict[str, Path], tmp_path: Path
) -> None:
    out = {}
    for name in ("short.glb", "tall.glb"):
        bvh = tmp_path / f"{name}.bvh"
        proc = run(
            "export",
            str(groove_dir / GROOVES[0]),
            "--map",
            "roland-td",
            "-o",
            str(bvh),
            "--fps",
            "10",
            "--avatar",
            str(files[name]),
        )
        assert proc.returncode == 0, proc.stderr
        out[name] = bvh.read_text()
    # the forearm offset (elbow -> wrist) is the avatar's: 0.26 m at 1.75 m, scaled
    for name, text in out.items():
        k = af.AVATARS[name].height_m / af.HEIGHT_M
        assert f"{-0.26 * k:.6f}" in text or f"{-0.26 * k:.4f}" in text, name


def test_avatar_info_text_and_json(files: dict[str, Path]) -> None:
    proc = run("avatar", "info", str(files["vrm0.vrm"]))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].endswith("VRM 0.x, 36 nodes, usable")
    text = proc.stdout
    assert "required missing none" in text and "faces -z, up +y" in text
    assert "r_wrist<-J_rightHand" in text and "420 triangles" in text
    assert "cloth (texture 4x4, OPAQUE, lit)" in text and "skin (colour, OPAQUE, toon)" in text
    proc = run("avatar", "info", str(files["mixamo.glb"]), "--json")
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout)
    assert info["convention"] == "Mixamo" and info["unit_scale"] == 0.01
    assert info["mapped"]["l_elbow"] == "mixamorig:LeftForeArm"
    assert info["proportions_m"]["forearm"] == pytest.approx(0.26 * 1.72 / 1.75, abs=1e-3)
    assert info["textures"] == 1 and info["triangles"] == 420


def test_avatar_info_of_an_unusable_file_says_why_and_exits_2(tmp_path: Path) -> None:
    path = af.write(tmp_path, "gap.vrm", af.Spec(vrm="1", drop=("rightFoot",)))
    proc = run("avatar", "info", str(path))
    assert proc.returncode == 2
    assert "required missing rightFoot" in proc.stdout
    assert proc.stderr.strip().splitlines() == [
        f"livedrummer: error: {path}: required bone(s) missing (VRM 1.0): rightFoot"
    ]


@pytest.mark.parametrize("command", ["check", "export", "render", "synth"])
def test_a_bad_avatar_is_one_line_and_exit_2(
    groove_dir: Path, tmp_path: Path, command: str
) -> None:
    bad = tmp_path / "bad.glb"
    bad.write_bytes(b"not a model at all")
    args = {
        "check": [str(groove_dir / GROOVES[0])],
        "export": [str(groove_dir / GROOVES[0]), "-o", str(tmp_path / "x.bvh")],
        "render": [str(groove_dir / GROOVES[0]), "-o", str(tmp_path / "x.mp4")],
        "synth": [],
    }[command]
    proc = run(command, *args, "--avatar", str(bad))
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines()[-1] == (
        f"livedrummer: error: {bad}: not a glTF file (neither GLB nor JSON text)"
    )


def test_an_avatar_too_small_for_the_kit_is_the_reach_error(
    groove_dir: Path, tmp_path: Path
) -> None:
    child = af.write(tmp_path, "child.vrm", af.Spec(height_m=0.9, vrm="1"))
    proc = run(
        "check",
        str(groove_dir / GROOVES[0]),
        "--map",
        "roland-td",
        "--avatar",
        str(child),
        "--fit",
        "none",
    )
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert "out of reach of the" in line and " mm" in line and f"with avatar {child}" in line
    assert "(--fit none; --fit auto would fit it: avatar x" in line


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A third-party-like VRM 1.0 of 0.66 m (a VRoid-sized model)."""
    return af.write(
        tmp_path_factory.mktemp("small"), "small.vrm", af.Spec(height_m=0.66, pose="A", vrm="1")
    )


@pytest.mark.parametrize("kit", ["rock5", "rock5-left"])
def test_a_small_vrm_plays_the_default_kit_fitted(groove_dir: Path, small: Path, kit: str) -> None:
    grooves = [str(groove_dir / g) for g in GROOVES]
    proc = run(
        "check",
        *grooves,
        "--map",
        "roland-td",
        "--kit",
        kit,
        "--avatar",
        str(small),
        "--json",
        "--summary",
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["notes"] > 500 and out["not_played"] == 0
    assert out["contact_error_mm"]["max"] <= 5.0
    assert out["penetration_mm"] <= 2.0
    fit = [line for line in proc.stderr.splitlines() if line.startswith("livedrummer: fit: ")]
    assert len(fit) == 1 and "avatar scaled x2." in fit[0] and "0.66 m -> 1." in fit[0]


def _snare(tmp_path: Path) -> Path:
    import mido

    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    for _ in range(2):
        track.append(mido.Message("note_on", channel=9, note=38, velocity=100, time=0))
        track.append(mido.Message("note_off", channel=9, note=38, velocity=0, time=240))
    mid.tracks.append(track)
    song = tmp_path / "snare.mid"
    mid.save(song)
    return song


@pytest.mark.parametrize("fit", ["auto", "kit"])
def test_avatar_info_predicts_what_render_and_check_do(
    groove_dir: Path, small: Path, tmp_path: Path, fit: str
) -> None:
    """auto scales the 0.66 m avatar; kit would have to move the kit x0.35 and refuses."""
    info = run("avatar", "info", str(small), "--fit", fit, "--json")
    said = json.loads(info.stdout)
    check = run(
        "check",
        str(groove_dir / GROOVES[0]),
        "--map",
        "roland-td",
        "--avatar",
        str(small),
        "--fit",
        fit,
        "--json",
        "--summary",
    )
    render = run(
        "render",
        str(_snare(tmp_path)),
        "--map",
        "general-midi",
        "--avatar",
        str(small),
        "--fit",
        fit,
        "--frames-dir",
        str(tmp_path / "f"),
        "--size",
        "64x36",
        "--fps",
        "5",
        "--tail",
        "0",
    )
    assert said["usable"] == (fit == "auto")
    for proc in (info, check, render):
        assert proc.returncode == (0 if said["usable"] else 2), proc.stderr
    if said["usable"]:
        line = f"livedrummer: fit: {said['fit']['said']}"
        assert said["fit"]["mode"] == "avatar"
        assert json.loads(check.stdout)["fit"] == said["fit"]
        assert line in check.stderr.splitlines() and line in render.stderr.splitlines()
        assert any((tmp_path / "f").glob("*.png"))
    else:
        error = f"livedrummer: error: {said['error']}"
        assert info.stderr.strip().splitlines()[-1] == error
        assert check.stderr.strip().splitlines()[-1] == error
        assert render.stderr.strip().splitlines()[-1] == error


def test_avatars_lists_built_in_and_user_files(tmp_path: Path) -> None:
    (tmp_path / "avatars").mkdir()
    af.write(tmp_path / "avatars", "vrm1.vrm")
    proc = run("avatars", "--json", LIVEDRUMMER_HOME=str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    found = {row["name"]: row for row in json.loads(proc.stdout)}
    assert found["default"]["kind"] == "built-in"
    assert found["vrm1"]["kind"] == "user"
    assert found["vrm1"]["path"] == str(tmp_path / "avatars" / "vrm1.vrm")
    proc = run("avatar", "info", "vrm1", LIVEDRUMMER_HOME=str(tmp_path))
    assert proc.returncode == 0 and "VRM 1.0" in proc.stdout


def test_render_draws_the_avatar(files: dict[str, Path], tmp_path: Path) -> None:
    import mido
    import numpy as np

    from livedrummer.avatar.gltf import decode_image

    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    for _ in range(4):
        track.append(mido.Message("note_on", channel=9, note=38, velocity=100, time=0))
        track.append(mido.Message("note_off", channel=9, note=38, velocity=0, time=240))
    mid.tracks.append(track)
    song = tmp_path / "snare.mid"
    mid.save(song)
    frames = {}
    for who in ("default", "tall.glb"):
        out = tmp_path / who
        avatar = [] if who == "default" else ["--avatar", str(files[who])]
        proc = run(
            "render",
            str(song),
            "--map",
            "general-midi",
            "--frames-dir",
            str(out),
            "--size",
            "160x90",
            "--fps",
            "10",
            "--tail",
            "0.2",
            "--camera",
            "front",
            *avatar,
        )
        assert proc.returncode == 0, proc.stderr
        png = sorted(out.glob("*.png"))[5]
        frames[who] = decode_image(png.read_bytes(), str(png))
    # the box-limbed 1.95 m avatar is not the built-in character
    diff = np.abs(frames["default"].astype(int) - frames["tall.glb"].astype(int)).sum(axis=-1)
    assert (diff > 60).mean() > 0.02


def test_up_gives_the_avatar_to_the_synth_and_the_display(
    files: dict[str, Path], tmp_path: Path
) -> None:
    from livedrummer.live.settings import ShowSettings
    from services.cli import build_parser
    from services.cli.settings import write_settings
    from services.cli.up import specs
    from services.cli.up_launch import resolve

    argv = ["up", "--demo", "--headless", "--avatar", str(files["vrm1.vrm"])]
    args = build_parser(argv).parse_args(argv)
    given = write_settings(resolve(args), tmp_path)
    by_name = {s.name: s.argv for s in specs(args, given)}
    for name in ("synth", "display"):  # the avatar is in the settings file each is given
        words = by_name[name]
        settings = ShowSettings.load(Path(words[words.index("--settings") + 1]))
        assert settings.avatar.spec == str(files["vrm1.vrm"].resolve()), name
        assert "--avatar" not in words, name
    display = by_name["display"]
    synth = by_name["synth"]
    # the display asks the synth's control socket which avatar it plays
    assert display[display.index("--synth-control") + 1] == synth[synth.index("--control") + 1]
    assert "--avatar" not in by_name["input"]
