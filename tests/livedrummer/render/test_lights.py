"""Show lights set in files, changed live and by cue: the pure parts (no GL, no socket).

``[lights]`` in kit, stage and preset files and their precedence; a light switched off; fades
between rigs on the stage's clock; OSC look and light commands turned into cues; cue lists
with a look, light parameters and a fade time, applied live and replayed. The pictures they
give are checked in ``tests/services/display/test_lights_live.py``.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import mido
import numpy as np
import pytest

from livedrummer.body.expression import PresetError, load_expression, preset_lights
from livedrummer.errors import KitError
from livedrummer.kit.lights import (
    DEFAULT_LOOK,
    LOOKS,
    LightError,
    LightSpec,
    blend_rigs,
    look_rig,
    resolve_lights,
    with_light_param,
)
from livedrummer.kit.loader import load_kit, load_kit_file
from livedrummer.live.cues import (
    Cue,
    CueError,
    fire_stage,
    parse_cues,
    stage_cue_of,
    stage_cue_rows,
    with_lights_of,
)
from livedrummer.live.stage import Stage
from livedrummer.stage.stagefile import StageError, load_stage
from services.display.showctl import DisplayShow, light_cue, replay_stage
from tests.conftest import MidiWriter

REPO = Path(__file__).resolve().parents[3]
ROCK5 = (REPO / "kits" / "rock5.toml").read_text()
KIT = load_kit("rock5")


def kit_with(tmp_path: Path, lights: str) -> Path:
    path = tmp_path / "lit.toml"
    path.write_text(ROCK5 + "\n" + lights)
    return path


def test_a_kit_file_sets_its_lights_and_a_typo_names_file_and_field(tmp_path: Path) -> None:
    path = kit_with(
        tmp_path,
        '[lights]\nlook = "studio"\nexposure = 1.2\n'
        '[lights.rim]\ncolor = "#ff0000"\nintensity = 5.0\n'
        "[lights.wash]\nenabled = false\ndirection = [30.0, 70.0]\n"
        "[lights.fill]\ncolor = [0.5, 0.25, 1.0]\n",
    )
    kit = load_kit_file(path)
    rig = resolve_lights(None, kit.lights)
    assert rig.name == "custom" and rig.exposure == 1.2
    assert rig.key == LOOKS["studio"].key
    assert rig.rim.color == (1.0, 0.0, 0.0) and rig.rim.intensity == 5.0
    assert not rig.wash.enabled and rig.wash.radiance == (0.0, 0.0, 0.0)
    assert (rig.wash.azimuth_deg, rig.wash.elevation_deg) == (30.0, 70.0)
    assert rig.fill.color == (0.5, 0.25, 1.0)
    assert load_kit("rock5").lights is None
    for text, match in (
        ("[lights.key]\nintensty = 2.0\n", r"\[lights.key\] intensty"),
        ("[lights.key]\nintensity = 50.0\n", r"\[lights.key\] intensity.*outside"),
        ('[lights]\nlook = "disco"\n', r"\[lights\] look"),
        ("[lights.spot]\nintensity = 1.0\n", r"\[lights\] spot"),
        ("[lights.rim]\ncolor = [2.0, 0.0, 0.0]\n", r"\[lights.rim\] color"),
        ("[lights.key]\nenabled = 1\n", r"\[lights.key\] enabled"),
    ):
        with pytest.raises(KitError, match=match) as err:
            load_kit_file(kit_with(tmp_path, text))
        assert str(err.value).startswith(str(tmp_path / "lit.toml")) and "\n" not in str(err.value)


def test_a_bad_kit_lights_table_is_one_line_and_exit_status_2(tmp_path: Path) -> None:
    path = kit_with(tmp_path, "[lights.key]\nelevation = 120.0\n")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            "--kit",
            str(path),
            "--frames-dir",
            str(tmp_path / "frames"),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "[lights.key] elevation" in lines[0] and str(path) in lines[0]


def test_stage_and_preset_files_set_lights_and_the_command_line_wins(tmp_path: Path) -> None:
    stage_path = tmp_path / "stage.toml"
    stage_path.write_text(
        '[[performer]]\nid = "a"\nfile = "a.mid"\n\n'
        '[lights]\nlook = "neon"\n[lights.key]\nintensity = 1.5\n'
    )
    stage = load_stage(stage_path)
    preset_path = tmp_path / "lit-preset.toml"
    preset_path.write_text(
        (REPO / "kits/presets/relaxed.toml").read_text()
        + '\n[lights]\nlook = "daylight"\n[lights.rim]\nintensity = 0.5\n'
        "[lights.fill]\nintensity = 0.7\n"
    )
    load_expression(str(preset_path))  # a preset with lights still plays
    preset = preset_lights(str(preset_path))
    kit = load_kit_file(
        kit_with(
            tmp_path,
            '[lights]\nlook = "studio"\n'
            "[lights.wash]\nintensity = 2.5\n"
            "[lights.rim]\nintensity = 4.0\n",
        )
    )
    assert preset_lights("relaxed") is None
    # default < kit < preset < stage < --look
    assert resolve_lights(None) == look_rig(DEFAULT_LOOK)
    only_kit = resolve_lights(None, kit.lights)
    assert only_kit.rim.intensity == 4.0 and only_kit.key == LOOKS["studio"].key
    kit_preset = resolve_lights(None, kit.lights, preset)
    assert kit_preset.key == LOOKS["daylight"].key and kit_preset.rim.intensity == 0.5
    all_three = resolve_lights(None, kit.lights, preset, stage.lights)
    assert all_three.key.intensity == 1.5 and all_three.fill == LOOKS["neon"].fill
    stage_over_kit = resolve_lights(None, kit.lights, None, LightSpec(changes=(("key", "r", 0.5),)))
    assert stage_over_kit.wash.intensity == 2.5 and stage_over_kit.key.color[0] == 0.5
    assert resolve_lights("concert", kit.lights, preset, stage.lights) == LOOKS["concert"]
    bad = tmp_path / "bad-preset.toml"
    bad.write_text("[expression]\n[lights.key]\nazimut = 3.0\n")
    with pytest.raises(PresetError, match=r"bad-preset.toml: \[lights.key\] azimut"):
        load_expression(str(bad))
    stage_path.write_text('[[performer]]\nid = "a"\nfile = "a.mid"\n[lights]\nexposure = 0\n')
    with pytest.raises(StageError, match=r"stage.toml: \[lights\] exposure"):
        load_stage(stage_path)


def test_a_light_switched_off_adds_nothing_and_keeps_its_settings() -> None:
    rig = with_light_param(LOOKS["concert"], "rim", "enabled", 0)
    assert rig.rim.radiance == (0.0, 0.0, 0.0)
    assert rig.rim.intensity == LOOKS["concert"].rim.intensity
    assert with_light_param(rig, "rim", "enabled", True).rim == LOOKS["concert"].rim
    for value in (2, 0.5, "on"):
        with pytest.raises(LightError, match="light rim enabled"):
            with_light_param(rig, "rim", "enabled", value)


def test_a_fade_mixes_two_rigs_the_short_way_round() -> None:
    a = with_light_param(LOOKS["concert"], "key", "azimuth", 170.0)
    b = with_light_param(
        with_light_param(LOOKS["neon"], "key", "azimuth", -170.0), "rim", "enabled", 0
    )
    assert blend_rigs(a, b, 0.0) == a and blend_rigs(a, b, 1.0) == b
    mid = blend_rigs(a, b, 0.5)
    assert mid.key.azimuth_deg == pytest.approx(180.0)  # across the back, not the front
    half = lambda u, v: tuple((x + y) / 2 for x, y in zip(u, v, strict=True))  # noqa: E731
    assert mid.key.color == pytest.approx(half(a.key.color, b.key.color))
    assert mid.rim.intensity == pytest.approx(a.rim.intensity / 2)  # fading out
    assert mid.exposure == pytest.approx((a.exposure + b.exposure) / 2)
    assert mid.sky == pytest.approx(half(a.sky, b.sky))


def test_the_stage_fades_its_lights_from_where_they_are() -> None:
    stage = Stage(KIT, "front", lights=LOOKS["studio"])
    assert stage.lights_at(0.0) == LOOKS["studio"]
    stage.set_lights(LOOKS["neon"], 10.0, fade_s=2.0)
    assert stage.lights_at(9.9) == LOOKS["studio"] and stage.lights_at(12.0) == LOOKS["neon"]
    half = stage.lights_at(11.0)  # the smoothstep's middle
    assert half == blend_rigs(LOOKS["studio"], LOOKS["neon"], 0.5)
    stage.set_lights(LOOKS["daylight"], 11.0, fade_s=1.0)  # a second change mid-fade
    assert stage.lights_at(11.0) == half and stage.lights_at(12.0) == LOOKS["daylight"]
    stage.set_lights(LOOKS["concert"], 13.0)  # no fade: at once
    assert stage.lights_at(13.0) == LOOKS["concert"]


def test_osc_look_and_light_commands_become_checked_cues() -> None:
    rig = LOOKS["concert"]
    cue = light_cue("/livedrummer/look", ("neon", 1.5), rig)
    assert cue.lights == LightSpec("neon") and cue.fade_s == 1.5
    for address, args, check in (
        ("/livedrummer/light/key/intensity", (4.0,), lambda r: r.key.intensity == 4.0),
        ("/livedrummer/light/fill/color", (1.0, 0.5, 0), lambda r: r.fill.color == (1, 0.5, 0)),
        ("/livedrummer/light/rim/color", ("#00ff00",), lambda r: r.rim.color == (0, 1, 0)),
        (
            "/livedrummer/light/wash/direction",
            (90, 45.0),
            lambda r: (r.wash.azimuth_deg, r.wash.elevation_deg) == (90, 45),
        ),
        ("/livedrummer/light/key/enabled", (False,), lambda r: not r.key.enabled),
        ("/livedrummer/light/key/g", (0.25, 3.0), lambda r: r.key.color[1] == 0.25),
    ):
        cue = light_cue(address, args, rig)
        assert cue.lights is not None and check(cue.lights.apply(rig)), address
    assert light_cue("/livedrummer/light/key/g", (0.25, 3.0), rig).fade_s == 3.0
    for address, args, match in (
        ("/livedrummer/look", ("disco",), "look 'disco'"),
        ("/livedrummer/look", (), "look name"),
        ("/livedrummer/look", ("neon", -1.0), "fade"),
        ("/livedrummer/light/spot/intensity", (1.0,), "LIGHT one of key"),
        ("/livedrummer/light/key", (1.0,), "LIGHT/PARAM"),
        ("/livedrummer/light/key/size", (1.0,), "light key size"),
        ("/livedrummer/light/key/intensity", (30.0,), "outside"),
        ("/livedrummer/light/key/intensity", ("bright",), "expected a number"),
        ("/livedrummer/light/key/color", (1.0, 0.0), "3 values"),
        ("/livedrummer/light/key/direction", (1.0, float("nan")), "not a number"),
        ("/livedrummer/light/key/enabled", (3,), "0 or 1"),
    ):
        with pytest.raises(ValueError, match=match):
            light_cue(address, args, rig)


def test_cues_set_a_look_and_light_parameters_with_a_fade() -> None:
    cues = parse_cues(
        {
            "cue": [
                {"name": "verse", "bar": 3, "look": "neon", "fade_s": 2.0},
                {
                    "name": "solo",
                    "bar": 5,
                    "camera": "front",
                    "lights": {"key": {"intensity": 6.0}, "rim": {"enabled": False}},
                },
                {"name": "sunrise", "lights": {"look": "daylight"}, "fade_s": 4.0},
            ]
        },
        "show.toml",
    )
    assert cues["verse"].lights == LightSpec("neon") and cues["verse"].stages
    stage = Stage(KIT, "stage")
    fire_stage(stage, cues["verse"], 1.0)
    assert stage.lights_at(2.0) == blend_rigs(LOOKS["concert"], LOOKS["neon"], 0.5)
    fire_stage(stage, cues["solo"], 3.0)  # over the lights in force: neon's
    lit = stage.lights_at(3.0)
    assert lit.key.intensity == 6.0 and not lit.rim.enabled and lit.fill == LOOKS["neon"].fill
    for cue, match in (
        ({"name": "x", "fade_s": 1.0}, "fade_s: fades a light change"),
        ({"name": "x", "look": "disco"}, "look"),
        ({"name": "x", "look": "neon", "lights": {"look": "studio"}}, "given twice"),
        ({"name": "x", "lights": {"key": {"intensty": 1.0}}}, r"\[cue 'x'.lights.key\] intensty"),
    ):
        with pytest.raises(CueError, match=match) as err:
            parse_cues({"cue": [cue]}, "show.toml")
        assert "show.toml" in str(err.value)


def test_a_bar_cues_lights_reach_the_display_from_its_own_cue_list() -> None:
    cues = parse_cues(
        {
            "cue": [
                {"name": "dim", "bar": 3, "lights": {"wash": {"intensity": 0.0}}, "fade_s": 0.5},
                {"name": "cut", "bar": 4, "camera": "front", "cut": True},
            ]
        },
        "t",
    )
    rows = stage_cue_rows([(1.0, 3, cues["dim"]), (2.0, 4, cues["cut"])])
    assert rows.size == 2, "a lights-only bar cue still tells the displays its bar"
    assert with_lights_of(stage_cue_of(rows[0]), cues).lights == cues["dim"].lights
    assert with_lights_of(stage_cue_of(rows[1]), cues) == stage_cue_of(rows[1])
    show = DisplayShow(KIT, "stage", None, cues=cues, lights=LOOKS["studio"])
    show.schedule(rows)
    seen = []
    for k in range(30):
        render = k * 0.1
        show.apply(render, render + 0.1)
        seen.append((render, show.stage.lights_at(render)))
    assert seen[8][1] == LOOKS["studio"]  # the frame shown at 0.9 s
    assert seen[-1][1].wash.intensity == 0.0 and seen[-1][1].key == LOOKS["studio"].key
    assert 0.0 < seen[10][1].wash.intensity < LOOKS["studio"].wash.intensity  # fading
    replay = replay_stage(KIT, show)
    for render, lights in seen:
        replay.at(render)
        assert replay.stage.lights_at(render) == lights
    assert Cue("x").lights is None and not Cue("x").stages


def test_look_is_passed_to_the_display_of_up_and_of_the_practice_rig(tmp_path: Path) -> None:
    from services.cli import build_parser
    from services.cli.practice_show import show_settings
    from services.cli.practice_show import specs as practice_specs
    from services.cli.settings import write_settings
    from services.cli.up import specs
    from services.cli.up_launch import resolve

    def up_specs(argv: list[str]) -> dict[str, list[str]]:
        args = build_parser(argv).parse_args(argv)
        return {s.name: s.argv for s in specs(args, write_settings(resolve(args), tmp_path))}

    argv = ["up", "--demo", "--headless", "--look", "neon", "--preset", "relaxed"]
    by_name = up_specs(argv)
    display = by_name["display"]
    assert display[display.index("--look") + 1] == "neon" and "--look" not in by_name["synth"]
    assert display[display.index("--preset") + 1] == "relaxed", "for the preset's [lights]"
    argv = ["up", "--demo", "--headless"]
    by_name = up_specs(argv)
    assert "--look" not in by_name["display"], "no --look: the display reads the kit's lights"
    groove = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"
    argv = ["practice", "play", str(groove), "--virtual", "x", "--headless", "--look", "studio"]
    args = build_parser(argv).parse_args(argv)
    given = write_settings(show_settings(args), tmp_path)
    by_name = {s.name: s.argv for s in practice_specs(args, "headless", "tcp://127.0.0.1:1", given)}
    display = by_name["display"]
    assert display[display.index("--look") + 1] == "studio"


def test_display_live_starts_from_the_kit_lights_under_look(gl_ok: None, tmp_path: Path) -> None:
    from tests.services.show.test_live_osc import read_png

    lit = kit_with(tmp_path, '[lights]\nlook = "neon"\n')

    def first_frame(name: str, *extra: str) -> np.ndarray:
        out = tmp_path / name
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "services",
                "display",
                "--live",
                "--headless",
                "--sub",
                "tcp://127.0.0.1:1",
                "--max-frames",
                "2",
                "--fps",
                "10",
                "--size",
                "160x90",
                "--frames-dir",
                str(out),
                *extra,
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert proc.returncode == 0, proc.stderr
        return read_png(out / "frame_000001.png").astype(int)

    flag = first_frame("flag", "--look", "neon")
    kit = first_frame("kit", "--kit", str(lit))
    over = first_frame("over", "--kit", str(lit), "--look", "concert")
    assert np.abs(flag - kit).mean() < 0.5, "a kit's look draws as --look draws it"
    assert np.abs(over - kit).mean() > 3.0, "--look wins over the kit's [lights]"


def test_render_fires_light_cues_with_their_fades(
    gl_ok: None, tmp_path: Path, write_midi: MidiWriter
) -> None:
    from tests.services.show.test_live_osc import read_png

    msgs = []
    for k in range(8):  # a snare each half second
        msgs.append(
            mido.Message("note_on", channel=9, note=38, velocity=90, time=0 if k == 0 else 480)
        )
        msgs.append(mido.Message("note_off", channel=9, note=38, velocity=0, time=0))
    midi = write_midi(msgs)
    cues = tmp_path / "cues.toml"
    off = "\n".join(f"[cue.lights.{n}]\nenabled = false" for n in ("key", "fill", "rim", "wash"))
    cues.write_text(
        f'[[cue]]\nname = "dark"\nat_s = 0.5\n{off}\n\n'
        '[[cue]]\nname = "up"\nat_s = 1.0\nlook = "studio"\nfade_s = 1.0\n'
    )
    out = tmp_path / "frames"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            str(midi),
            "--frames-dir",
            str(out),
            "--size",
            "160x90",
            "--fps",
            "10",
            "--tail",
            "0.5",
            "--cues",
            str(cues),
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    mean = {i: read_png(out / f"frame_{i:06d}.png").astype(float).mean() for i in (4, 7, 15, 22)}
    assert mean[7] < 0.5 * mean[4], "the lights are off from 0.5 s"
    assert mean[7] < mean[15] < mean[22], "and fade up to studio over 1.0 s to 2.0 s"


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_the_file_window_is_lit_by_look_and_by_the_kit(tmp_path: Path) -> None:
    from tests.services.show.test_live_osc import read_png

    lit = kit_with(tmp_path, '[lights]\nlook = "neon"\n')

    def shot(name: str, *extra: str) -> np.ndarray:
        png = tmp_path / f"{name}.png"
        run = subprocess.run(
            [
                "xvfb-run",
                "-a",
                "-s",
                "-screen 0 640x360x24",
                sys.executable,
                "-m",
                "services",
                "display",
                "--size",
                "320x180",
                "--aa",
                "0",
                "--camera",
                "front",
                "--seconds",
                "0.5",
                "--no-sound",
                "--screenshot",
                str(png),
                *extra,
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stderr
        return read_png(png).astype(float)

    def magenta(im: np.ndarray) -> float:  # neon's key is magenta, its rim violet
        return float((im[..., 0].mean() + im[..., 2].mean()) / (2 * im[..., 1].mean() + 1))

    concert = magenta(shot("concert"))
    assert magenta(shot("flag", "--look", "neon")) > 1.2 * concert
    assert magenta(shot("kit", "--kit", str(lit))) > 1.2 * concert
    assert magenta(shot("over", "--kit", str(lit), "--look", "concert")) < 1.1 * concert
