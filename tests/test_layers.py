"""The architecture holds: the library imports no process code, and the wheel ships one package.

Layers: ``livedrummer/`` is pure logic and never imports ``services`` (processes, devices,
sockets, windows, the CLI and the benchmarks). ``services/`` imports its own modules
relatively, because an installed wheel carries it as ``livedrummer._services``
(pyproject.toml, deploy/wheel_hook.py). The wheel test builds the real wheel, installs it into
a fresh virtual environment that sees the dependencies but not this checkout, and runs the
command from there.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
UPPER = {"services", "bench", "tests"}


def imports(path: Path) -> list[tuple[int, str, int]]:
    """(line, module, level) of every import statement in ``path``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, 0) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            out.append((node.lineno, node.module or "", node.level))
    return out


def test_the_library_imports_no_process_code() -> None:
    bad = [
        f"{f.relative_to(REPO)}:{line}: {name}"
        for f in sorted((REPO / "livedrummer").rglob("*.py"))
        for line, name, level in imports(f)
        if level == 0 and name.split(".")[0] in UPPER
    ]
    assert bad == []


def test_the_process_layer_imports_itself_relatively() -> None:
    bad = [
        f"{f.relative_to(REPO)}:{line}: {name}"
        for f in sorted((REPO / "services").rglob("*.py"))
        for line, name, level in imports(f)
        if level == 0 and name.split(".")[0] in UPPER
    ]
    assert bad == []
    assert (REPO / "services" / "__main__.py").is_file()


def test_the_flat_root_holds_only_infrastructure() -> None:
    flat = sorted(p.name for p in (REPO / "livedrummer").glob("*.py"))
    assert flat == ["__init__.py", "config.py", "errors.py", "resources.py"]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                    "--no-build-isolation", "-w", str(out), str(REPO)],
                   check=True, capture_output=True, timeout=300)  # fmt: skip
    (built,) = out.glob("livedrummer-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A virtual environment with the wheel, the dependencies, and no path to this checkout."""
    env = tmp_path_factory.mktemp("venv")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env)], check=True)
    python = env / "bin" / "python"
    purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()"
                              "['purelib'])"], capture_output=True, text=True, check=True)  # fmt: skip
    # A plain path line: the dependencies' folder is on sys.path, but its .pth files (the
    # editable install of this checkout among them) are not run.
    Path(purelib.stdout.strip(), "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
                    "--no-deps", str(wheel)], check=True, capture_output=True, timeout=300)  # fmt: skip
    return env


def test_the_wheel_puts_only_livedrummer_into_site_packages(wheel: Path) -> None:
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {"livedrummer", wheel.name.split("-py")[0]
                                                + ".dist-info"}  # fmt: skip
    assert "livedrummer/_services/cli/__init__.py" in names
    assert "livedrummer/_services/bench/jack_ref.c" in names
    assert "livedrummer/_data/kits/rock5.toml" in names
    assert not [n for n in names if "__pycache__" in n]
    entry = next(n for n in names if n.endswith("entry_points.txt"))
    assert "livedrummer = livedrummer._services.cli:main" in zipfile.ZipFile(wheel).read(
        entry).decode()  # fmt: skip


#: The environment of the installed runs: no PYTHONPATH, which could lead back to a checkout.
CLEAN_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def run_installed(env: Path, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(env / "bin" / "livedrummer"), *args], capture_output=True,
                          text=True, timeout=120, cwd=cwd, env=CLEAN_ENV)  # fmt: skip


def test_the_installed_command_works_without_the_checkout(installed: Path, tmp_path: Path) -> None:
    probe = subprocess.run([str(installed / "bin" / "python"), "-c", "import services"],
                           capture_output=True, text=True, cwd=tmp_path, env=CLEAN_ENV)  # fmt: skip
    assert probe.returncode != 0  # the checkout is not reachable from this environment
    assert run_installed(installed, "--help", cwd=tmp_path).returncode == 0
    kits = run_installed(installed, "kits", cwd=tmp_path)
    assert kits.returncode == 0 and "_data/kits/rock5.toml" in kits.stdout
    groove = next((REPO / "kits" / "grooves").glob("*.mid"))
    seen = run_installed(installed, "inspect", str(groove), "--json", cwd=tmp_path)
    assert seen.returncode == 0, seen.stderr
    assert '"onsets"' in seen.stdout


def test_bench_from_the_wheel_names_the_corpus_to_pass(installed: Path, tmp_path: Path) -> None:
    run = run_installed(installed, "bench", "ingest", cwd=tmp_path)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "--corpus DIR" in lines[0] and "installed wheel" in lines[0]
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    for f in sorted((REPO / "kits" / "grooves").glob("*.mid"))[:2]:
        (corpus / f.name).write_bytes(f.read_bytes())
    done = run_installed(installed, "bench", "ingest", "--corpus", str(corpus), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "onsets/s" in done.stdout
