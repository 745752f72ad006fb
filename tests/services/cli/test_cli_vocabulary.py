"""One vocabulary on the command line: one name per meaning, every default stated, former
spellings still accepted (hidden, with a warning), and a start-up that imports no numpy."""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from livedrummer.sticking import STRATEGIES
from services.cli import COMMANDS, build_parser, command_named
from services.cli.parsing import help_with_default
from services.cli.performer import STICKING_STRATEGIES

REPO = Path(__file__).resolve().parents[3]

#: (command words, former spelling, current spelling, words after the option)
RENAMED = [
    (["sticking", "x.mid"], "--strategy", "--sticking", []),
    (["display"], "--quit-after", "--seconds", []),
    (["display"], "--frames", "--max-frames", []),
    (["display"], "--out", "--frames-dir", []),
    (["render"], "--frames", "--frames-dir", []),
    (["up", "--demo"], "--out", "--frames-dir", []),
    (["demo"], "--file", "--offline", []),
    (["demo"], "--render", "--headless", []),
    (["sessions"], "--dir", "--sessions-dir", ["list"]),
    (["keys", "new", "NAME"], "--dir", "--keys-dir", []),
    (["keys", "list"], "--dir", "--keys-dir", []),
]


def parsers(
    p: argparse.ArgumentParser, path: str = ""
) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    yield path, p
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sp in a.choices.items():
                yield from parsers(sp, f"{path} {name}".strip())


def options(p: argparse.ArgumentParser) -> Iterator[argparse.Action]:
    """The options ``--help`` shows (not -h, not hidden former spellings)."""
    for a in p._actions:
        if a.option_strings and a.help is not argparse.SUPPRESS and a.dest != "help":
            yield a


def required_groups(p: argparse.ArgumentParser) -> set[int]:
    return {id(a) for g in p._mutually_exclusive_groups if g.required for a in g._group_actions}


def test_every_option_states_its_default() -> None:
    missing = []
    for path, p in parsers(build_parser()):
        must_choose = required_groups(p)
        for a in options(p):
            if a.nargs == 0 or a.required or id(a) in must_choose or a.dest == "version":
                continue  # flags are off by default; a required option has none
            text = help_with_default(a)
            if "default" not in text:
                missing.append(f"{path} {a.option_strings[-1]}")
            elif isinstance(a.default, int | float | str) and "(default" in (a.help or ""):
                shown = f"{a.default:g}" if isinstance(a.default, float) else str(a.default)
                assert shown in text, f"{path} {a.option_strings[-1]}: says {text!r}"
    assert not missing


def test_one_name_one_kind_of_value() -> None:
    """An option spelled the same in several commands is a flag everywhere or a value everywhere."""
    takes: dict[str, set[bool]] = {}
    for _, p in parsers(build_parser()):
        for a in options(p):
            for name in a.option_strings:
                takes.setdefault(name, set()).add(a.nargs != 0)
    assert {name for name, kinds in takes.items() if len(kinds) > 1} == set()


def test_former_spellings_are_hidden_and_still_work(capsys: pytest.CaptureFixture[str]) -> None:
    full = dict(parsers(build_parser()))
    for words, old, new, after in RENAMED:
        where = " ".join(words[:2]) if " ".join(words[:2]) in full else words[0]
        p = full[where]
        visible = {n for a in options(p) for n in a.option_strings}
        assert old not in visible and f"{old} " not in p.format_help(), (where, old)
        current = next(a for a in options(p) if new in a.option_strings)
        value = [] if current.nargs == 0 else ["7"]
        a = build_parser().parse_args([*words, old, *value, *after])
        assert f"{old} is now spelled {new}" in capsys.readouterr().err
        b = build_parser().parse_args([*words, new, *value, *after])
        assert vars(a) == vars(b), (where, old)
    # no former spelling is still shown anywhere, but input's --file (a MIDI file to play,
    # always a value; demo's --file was a flag)
    shown = {n for _, p in full.items() for a in options(p) for n in a.option_strings}
    assert {old for _, old, _, _ in RENAMED} & shown == {"--file"}


def test_a_former_spelling_warns(capsys: pytest.CaptureFixture[str]) -> None:
    build_parser(["display"]).parse_args(["display", "--quit-after", "2"])
    assert "--quit-after is now spelled --seconds" in capsys.readouterr().err


def test_sticking_strategies_named_for_the_parser_are_the_library_s() -> None:
    assert tuple(STRATEGIES) == STICKING_STRATEGIES


def test_every_command_registers_with_its_one_line_help() -> None:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == list(COMMANDS)
    for name, p in sub.choices.items():
        assert p.description == COMMANDS[name]
        assert p.get_default("func") is not None, name


def test_only_the_named_command_is_built() -> None:
    assert command_named(["-v", "kits"]) == "kits"
    assert command_named(["--help"]) is None and command_named(["nope"]) is None
    sub = next(
        a for a in build_parser(["kits"])._actions if isinstance(a, argparse._SubParsersAction)
    )
    assert sub.choices["kits"].get_default("func") is not None
    assert list(sub.choices) == ["kits"]  # nothing else is built
    stubs = next(
        a for a in build_parser(["--help"])._actions if isinstance(a, argparse._SubParsersAction)
    )
    assert list(stubs.choices) == list(COMMANDS)
    assert stubs.choices["render"].get_default("func") is None  # a stub, listed by --help


@pytest.mark.parametrize("argv", [["--help"], ["kits"]])
def test_help_and_kits_load_no_numpy_and_no_services(argv: list[str]) -> None:
    # The CLI is part of the process layer; only its own parser modules may be loaded.
    code = (
        "import sys\n"
        "from services.cli import main\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        "cli = {'services', 'services.cli', 'services.cli.commands', 'services.cli.parsing', 'services.cli.kits'}\n"
        "heavy = sorted(m for m in sys.modules if m.split('.')[0] in "
        "('numpy', 'services', 'zmq', 'mido', 'moderngl') and m not in cli)\n"
        "print('HEAVY', heavy, file=sys.stderr)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60
    )
    assert "HEAVY []" in proc.stderr, proc.stderr
    assert ("kits:" if argv == ["kits"] else "COMMAND") in proc.stdout


def test_display_live_stops_after_seconds_as_up_does(tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "display",
            "--live",
            "--headless",
            "--no-render",
            "--sub",
            "tcp://127.0.0.1:1",
            "--seconds",
            "1",
            "--frames-dir",
            str(tmp_path),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0, proc.stderr
    assert "display: " in proc.stderr and (tmp_path / "frames.jsonl").exists()
