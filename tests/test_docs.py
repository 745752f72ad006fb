"""The documentation site: a real ``mkdocs build --strict`` and the README that points into it.

The build runs the MkDocs hook (``deploy/docs_hooks.py``) that generates the command-line,
wire-protocol and file-format references from the code, so a link that breaks, a page left out
of the nav or a generator that fails makes this test fail, as it fails ``make docs``. The built
pages are then read back for what they must name: every subcommand (nested ones and every
benchmark included), the protocol's version and every message kind, every expression parameter.
"""

from __future__ import annotations

import html
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

from livedrummer.body.expression import PARAMS
from livedrummer.protocol.spec import PROTOCOL_VERSION, Kind
from services.cli import COMMANDS

REPO = Path(__file__).resolve().parent.parent
README_MAX_LINES = 250


def _hooks() -> ModuleType:
    spec = importlib.util.spec_from_file_location("docs_hooks", REPO / "deploy" / "docs_hooks.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return out


def _text(page: Path) -> str:
    return html.unescape(re.sub(r"<[^>]+>", " ", page.read_text(encoding="utf-8")))


def test_the_site_builds_strictly_with_every_page(site: Path) -> None:
    for page in (
        "index",
        "reference/cli",
        "reference/wire",
        "reference/stage-file",
        "reference/kit-files",
        "reference/presets",
        "reference/show-files",
        "receiver",
        "benchmarks/index",
    ):
        assert (site / f"{page}.html").is_file(), page


def test_the_cli_page_names_every_subcommand(site: Path) -> None:
    text = _text(site / "reference" / "cli.html")
    for name in COMMANDS:
        assert f"livedrummer {name}" in text, name
    for nested in (
        "practice score",
        "practice history",
        "map learn",
        "keys new",
        "sessions export",
        "deploy systemd",
        "bench latency",
        "bench transcribe",
    ):
        assert f"livedrummer {nested}" in text, nested
    assert "--delay-ms" in text and "--lookahead-ms" in text


def test_the_wire_page_is_the_spec(site: Path) -> None:
    text = _text(site / "reference" / "wire.html")
    assert f"Protocol version {PROTOCOL_VERSION}" in " ".join(text.split())
    for kind in Kind:
        assert re.search(rf"\b{int(kind)}\s+{kind.name}\b", text), kind.name
    # the example's bytes, as the codec wrote them at build time: magic, version, kind ONSET
    assert f"4c 44 52 4d {PROTOCOL_VERSION:02x} {int(Kind.ONSET):02x}" in text


def test_the_presets_page_lists_every_parameter(site: Path) -> None:
    text = _text(site / "reference" / "presets.html")
    for p in PARAMS:
        assert p.name in text, p.name


def test_a_kind_without_a_meaning_stops_the_build() -> None:
    hooks = _hooks()
    del hooks.KIND_MEANING["STAGE_CUE"]
    with pytest.raises(ValueError, match="STAGE_CUE"):
        hooks.wire_markdown()


def test_the_readme_is_short_and_its_links_into_docs_exist() -> None:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= README_MAX_LINES
    assert readme.startswith("# livedrummer\n")
    assert "```sh\nmake demo\nmake test\n```" in readme  # the two commands CI and reviewers use
    links = re.findall(r"\]\(((?:docs/)[^)#\s]+)", readme)
    assert len(links) >= 10
    for link in links:
        assert (REPO / link).is_file(), link


def test_the_osc_page_names_every_address_served() -> None:
    from services.show.osc import DISPLAY_ADDRESSES, STATE, SYNTH_ADDRESSES

    page = (REPO / "docs" / "reference" / "osc.md").read_text(encoding="utf-8")
    documented = set(re.findall(r"^\| `(/livedrummer/[^`]*)`", page, re.M))
    served = {
        a.replace("param/", "param/NAME").replace("light/", "light/L/P")
        for a in (*SYNTH_ADDRESSES, *DISPLAY_ADDRESSES)
    }
    assert documented == served | {STATE}
