"""The marks tests/markers.py gives: e2e and gpu from what a test's code reaches, slow by name."""

from __future__ import annotations

import ast
from pathlib import Path

import markers
from markers import SLOW, marks_of

REPO = Path(__file__).resolve().parent.parent


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "test_sample.py"
    path.write_text(text)
    return path


SAMPLE = """
import subprocess

import pytest
import zmq


def start(args):
    return subprocess.Popen(args)


def helper():
    return start(["true"])


@pytest.fixture
def sub_socket():
    return zmq.Context.instance().socket(zmq.SUB)


def test_pure():
    assert 1 + 1 == 2


def test_through_a_helper():
    helper().wait()


def test_with_the_socket(sub_socket):
    assert sub_socket


def test_draws(gl_ok):
    pass


def test_renders():
    assert main(["render", "x.mid"]) == 0


def test_runs_up():
    assert main(["up", "--demo"]) == 0


def test_lists_kits():
    assert main(["kits"]) == 0


class TestGroup:
    def test_method_through_a_helper(self):
        helper()
"""


def test_a_pure_test_gets_no_mark(tmp_path: Path) -> None:
    path = write(tmp_path, SAMPLE)
    assert marks_of(path, "test_pure", ["tmp_path"]) == frozenset()
    assert marks_of(path, "test_lists_kits", []) == frozenset()


def test_a_process_reached_through_helpers_or_fixtures_is_e2e(tmp_path: Path) -> None:
    path = write(tmp_path, SAMPLE)
    assert marks_of(path, "test_through_a_helper", []) == {"e2e"}
    assert marks_of(path, "TestGroup.test_method_through_a_helper", []) == {"e2e"}
    assert marks_of(path, "test_with_the_socket", ["sub_socket"]) == {"e2e"}
    assert marks_of(path, "test_runs_up", []) == {"e2e"}
    assert marks_of(path, "test_pure", ["jack_server"]) == {"e2e"}


def test_a_gl_context_is_gpu(tmp_path: Path) -> None:
    path = write(tmp_path, SAMPLE)
    assert marks_of(path, "test_draws", ["gl_ok"]) == {"gpu"}
    assert marks_of(path, "test_renders", []) == {"gpu"}


def test_helpers_imported_from_other_test_and_process_modules_are_followed() -> None:
    # tests/test_layers.py's wheel tests build and install a wheel through subprocess
    layers = REPO / "tests" / "test_layers.py"
    assert "e2e" in marks_of(
        layers,
        "test_the_installed_command_works_without_the_checkout",
        ["installed", "tmp_path", "wheel"],
    )
    assert marks_of(layers, "test_cycles_finds_a_loop_and_nothing_else", []) == frozenset()
    assert markers._source_of("services.no_such_module") is None
    assert markers._source_of("livedrummer.kit") is None  # the library is not followed


def test_a_name_imported_from_services_is_read_in_its_own_module(tmp_path: Path) -> None:
    # the flood benchmark starts an input daemon and a subscriber
    path = write(
        tmp_path,
        "from services.bench.flood import run_flood\n\n\ndef test_floods():\n    run_flood()\n",
    )
    assert marks_of(path, "test_floods", []) == {"e2e"}


def test_every_slow_entry_names_a_test_that_exists() -> None:
    defined = set()
    for f in (REPO / "tests").rglob("test_*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
                defined.add(f"{f.name}::{node.name}")
    assert sorted(SLOW - defined) == []
