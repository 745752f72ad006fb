"""The show's settings resolved once: exact round trips, strict reading, one delay check."""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from livedrummer.live.settings import (
    AvatarChoice,
    Delay,
    DelayError,
    SettingsError,
    ShowSettings,
    Sound,
    check_delay,
)
from livedrummer.live.synth import SynthParams

REPO = Path(__file__).resolve().parents[3]

FULL = ShowSettings(
    note_map="general-midi",
    kit="/kits/my kit.toml",
    avatar=AvatarChoice("/avatars/tall.glb", "/avatars/tall.bones.toml", "kit"),
    delay=Delay(lookahead_s=0.025, delay_s=0.0625),
    sound=Sound(True, "/sounds/kit.sfz", "system, JACK"),
)


@pytest.mark.parametrize("settings", [FULL, ShowSettings("roland-td")], ids=["full", "defaults"])
def test_settings_round_trip_through_json_and_toml_exactly(
    settings: ShowSettings, tmp_path: Path
) -> None:
    back = ShowSettings.load(settings.save(tmp_path / "s.json"))
    assert back == settings
    assert back.digest() == settings.digest()
    # the dict form holds no null, so TOML carries it as well as JSON
    toml = "\n".join(_toml(settings.to_dict()))
    assert ShowSettings.from_dict(tomllib.loads(toml), "s.toml") == settings


def _toml(data: dict[str, object]) -> list[str]:
    flat = [f"{k} = {json.dumps(v)}" for k, v in data.items() if not isinstance(v, dict)]
    tables = [
        line
        for k, v in data.items()
        if isinstance(v, dict)
        for line in [f"[{k}]", *(f"{kk} = {json.dumps(vv)}" for kk, vv in v.items())]
    ]
    return flat + tables


def test_the_digest_tells_apart_settings_that_differ_in_one_field() -> None:
    other = ShowSettings(**{**FULL.__dict__, "note_map": "roland-td"})
    assert other.digest() != FULL.digest()
    assert FULL.summary() == {
        "map": "general-midi",
        "kit": "/kits/my kit.toml",
        "delay_ms": 62.5,
        "lookahead_ms": 25.0,
        "digest": FULL.digest(),
    }


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["delay"].update(delay_ms=10.0),
         "s.json: [delay] lookahead_ms 25 must be between 0 and delay_ms 10"),
        (lambda d: d["delay"].update(dealy_ms=1.0),
         "s.json: [delay] dealy_ms: unknown key; did you mean 'delay_ms'?"),
        (lambda d: d.update(note_map="auto"), "s.json: note_map 'auto': a resolved map"),
        (lambda d: d.update(version=7), "s.json: [] version: this livedrummer reads version 1"),
        (lambda d: d.update(format="kit"), "s.json: [] format: expected"),
        (lambda d: d["avatar"].update(fit="stretch"), "s.json: [avatar] fit: must be one of"),
        (lambda d: d["sound"].update(on="yes"), "s.json: [sound] on: expected true or false"),
        (lambda d: d.pop("kit"), "s.json: [] kit: missing required key"),
        (lambda d: d.update(kits=1), "s.json: [] kits: unknown key; did you mean 'kit'?"),
    ],
)  # fmt: skip
def test_a_bad_settings_file_is_one_error_naming_the_file_and_field(edit, message: str) -> None:  # type: ignore[no-untyped-def]
    data = FULL.to_dict()
    edit(data)
    with pytest.raises(SettingsError) as err:
        ShowSettings.from_json(json.dumps(data), "s.json")
    assert str(err.value).startswith(message), str(err.value)
    assert "\n" not in str(err.value)


def test_not_json_names_the_line() -> None:
    with pytest.raises(SettingsError, match=r"^s.json: line 2: not JSON"):
        ShowSettings.from_json('{\n  "format": ,\n}', "s.json")


def test_the_delay_is_checked_in_one_place_naming_the_callers_fields() -> None:
    with pytest.raises(DelayError, match=r"^--lookahead-ms 40 must be between 0 and --delay-ms 30"):
        Delay.from_ms(40.0, 30.0, ("--lookahead-ms", "--delay-ms"))
    with pytest.raises(DelayError, match="lookahead_ms -1 must be between 0"):
        Delay(-0.001, 0.03)
    with pytest.raises(DelayError, match="delay_ms nan: expected a finite"):
        check_delay(0.0, float("nan"))
    # the synth's parameters are checked by the same function (a ValueError, as always)
    with pytest.raises(ValueError, match="lookahead_ms 50 must be between 0 and delay_ms 30"):
        SynthParams(lookahead_s=0.05, delay_s=0.03)
    Delay(0.0, 0.0)
    Delay(0.03, 0.03)


def test_a_service_given_a_bad_settings_file_says_one_line_and_exits_2(tmp_path: Path) -> None:
    data = FULL.to_dict()
    data["delay"]["delay_ms"] = 5.0
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    for argv in (
        ["synth", "--settings", str(bad)],
        ["input", "--file", str(REPO / "kits"), "--settings", str(bad)],
        ["display", "--live", "--headless", "--settings", str(bad)],
    ):
        proc = subprocess.run(
            [sys.executable, "-m", "services", *argv],
            capture_output=True,
            text=True,
            cwd=REPO,
            timeout=60,
        )
        assert proc.returncode == 2, (argv, proc.stderr)
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1, (argv, proc.stderr)
        assert f"{bad}: [delay] lookahead_ms 25 must be between 0 and delay_ms 5" in lines[0]


def test_a_flag_given_beside_a_settings_file_is_refused(tmp_path: Path) -> None:
    path = FULL.save(tmp_path / "s.json")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "synth",
            "--settings",
            str(path),
            "--delay-ms",
            "80",
            "--kit",
            "jazz4",
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().endswith(
        f"--settings {path}: --kit, --delay-ms given beside it; the file holds them "
        "(give one or the other)"
    ), proc.stderr


def test_an_audio_input_refuses_settings_with_another_map_than_it_writes(tmp_path: Path) -> None:
    path = ShowSettings("roland-td").save(tmp_path / "s.json")
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "input",
            "--audio",
            "system",
            "--settings",
            str(path),
            "--no-journal",
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"livedrummer: error: --settings {path}: note_map 'roland-td': --audio writes "
        "general-midi notes"
    ], proc.stderr
