"""The architecture holds: the package order, no import cycle, and a wheel that ships one package.

Layers: ``livedrummer/`` is pure logic and never imports ``services`` (processes, devices,
sockets, windows, the CLI and the benchmarks). Inside the library the packages form one order
(:data:`LIBRARY_ORDER`, lowest first): a package imports only packages below it, so none
reaches back up (a back-edge) and the package graph has no cycle; a new package must be given
its place in the order. Below the packages no two modules import each other, directly or round
a loop, anywhere in ``livedrummer/`` or ``services/``, nor do two packages of ``services/``:
every import counts, one inside a function or under ``TYPE_CHECKING`` too, because a lazy
import is a dependency all the same. ``services/`` imports its own modules relatively, because
an installed wheel carries it as ``livedrummer._services`` (pyproject.toml,
deploy/wheel_hook.py). The wheel test builds the real wheel, installs it into a fresh virtual
environment that sees the dependencies but not this checkout, and runs the command from there.
"""

from __future__ import annotations

import ast
import functools
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


def test_the_library_root_holds_only_infrastructure() -> None:
    flat = sorted(p.name for p in (REPO / "livedrummer").glob("*.py"))
    assert flat == ["__init__.py", "config.py", "errors.py", "resources.py"]


def test_the_process_root_holds_only_its_entry_points() -> None:
    assert sorted(p.name for p in (REPO / "services").glob("*.py")) == sorted(SERVICES_ROOT)


#: The library's packages and root modules, lowest first: each imports only those before it.
LIBRARY_ORDER = (
    "errors",
    "resources",
    "config",
    "native",
    "kit",
    "timeline",
    "midi",
    "protocol",
    "audio",
    "sticking",
    "body",
    "render",
    "live",
    "stage",
    "avatar",
    "acoustic",
    "practice",
)

# BEGIN KNOWN CYCLES (none: services/ is sorted)
KNOWN_MODULE_CYCLES: set[tuple[str, ...]] = set()
#: services/cli dispatches the benchmarks (livedrummer bench NAME) and the benchmarks reuse
#: the commands' own pieces (the demo groove, --size, the render command's scene), so
#: that they measure what a user runs: the one package cycle that stands.
KNOWN_PACKAGE_CYCLES: set[tuple[str, ...]] = {("services.bench", "services.cli")}
#: Modules that may sit at the root of services/.
SERVICES_ROOT = {"__init__.py", "__main__.py"}
# END KNOWN CYCLES


def modules(top: str) -> dict[str, Path]:
    """Every module under ``top`` by dotted name (a package by its own name)."""
    out = {}
    for f in sorted((REPO / top).rglob("*.py")):
        parts = f.relative_to(REPO).with_suffix("").parts
        out[".".join(parts[:-1] if f.name == "__init__.py" else parts)] = f
    return out


def import_graph(*tops: str) -> dict[str, set[tuple[str, int]]]:
    """Module → the (module, line) pairs it imports, of the modules under ``tops``."""
    return {m: t for m, t in whole_graph().items() if m.split(".")[0] in tops}


@functools.cache
def whole_graph() -> dict[str, set[tuple[str, int]]]:
    """Module → the (module, line) pairs it imports, within ``livedrummer/`` and ``services/``;
    relative imports resolved, ``from package import module`` counted as the module, a name
    inside a module as the module."""
    known = {name: f for top in ("livedrummer", "services") for name, f in modules(top).items()}
    graph: dict[str, set[tuple[str, int]]] = {name: set() for name in known}
    for name, f in known.items():
        here = name.split(".") if f.name == "__init__.py" else name.split(".")[:-1]
        for line, module, level in imports(f):
            base = here[: len(here) - level + 1] if level else []
            target = ".".join(base + ([module] if module else []))
            graph[name].add((target, line))
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.ImportFrom):
                base = here[: len(here) - node.level + 1] if node.level else []
                target = ".".join(base + ([node.module] if node.module else []))
                graph[name] |= {(f"{target}.{a.name}", node.lineno) for a in node.names}
    resolved: dict[str, set[tuple[str, int]]] = {}
    for name, targets in graph.items():
        resolved[name] = set()
        for target, line in targets:
            while target and target not in known:
                target = target.rpartition(".")[0]
            if target and target != name:
                resolved[name].add((target, line))
    return resolved


def cycles(graph: dict[str, set[str]]) -> set[tuple[str, ...]]:
    """The strongly connected components of more than one node (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: set[tuple[str, ...]] = set()

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while (w := stack.pop()) != v:
                part.append(w)
            if part:
                out.add(tuple(sorted([*part, v])))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def package_of(module: str) -> str:
    """``livedrummer.midi.smf`` → ``livedrummer.midi``; a root module is its own package."""
    return ".".join(module.split(".")[:2])


def test_cycles_finds_a_loop_and_nothing_else() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert cycles(graph) == {("a", "b", "c")}


def test_library_packages_import_only_downwards() -> None:
    graph = import_graph("livedrummer")
    packages = {package_of(m).removeprefix("livedrummer.") for m in graph} - {"livedrummer"}
    assert sorted(packages - set(LIBRARY_ORDER)) == []  # a new package needs its place
    rank = {name: i for i, name in enumerate(LIBRARY_ORDER)}
    back = sorted(
        f"{modules('livedrummer')[src].relative_to(REPO)}:{line}: {dst}"
        for src, targets in graph.items()
        for dst, line in targets
        if src != "livedrummer" and dst != "livedrummer"
        if package_of(src) != package_of(dst)
        and rank[package_of(src).split(".")[1]] < rank[package_of(dst).split(".")[1]]
    )
    assert back == []


def test_no_two_modules_import_each_other() -> None:
    graph = import_graph("livedrummer", "services")
    found = cycles({m: {t for t, _ in targets} for m, targets in graph.items()})
    assert found == KNOWN_MODULE_CYCLES


def test_no_two_process_packages_import_each_other() -> None:
    graph: dict[str, set[str]] = {}
    for src, targets in import_graph("services").items():
        here = package_of(src)
        graph.setdefault(here, set())
        graph[here] |= {package_of(t) for t, _ in targets if package_of(t) != here}
    assert cycles(graph) == KNOWN_PACKAGE_CYCLES


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--quiet",
            "--no-deps",
            "--no-build-isolation",
            "-w",
            str(out),
            str(REPO),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (built,) = out.glob("livedrummer-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A virtual environment with the wheel, the dependencies, and no path to this checkout."""
    env = tmp_path_factory.mktemp("venv")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env)], check=True)
    python = env / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    )
    # A plain path line: the dependencies' folder is on sys.path, but its .pth files (the
    # editable install of this checkout among them) are not run.
    Path(purelib.stdout.strip(), "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(python),
            "install",
            "--quiet",
            "--no-deps",
            str(wheel),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    return env


def test_the_wheel_puts_only_livedrummer_into_site_packages(wheel: Path) -> None:
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names} == {
        "livedrummer",
        wheel.name.split("-py")[0] + ".dist-info",
    }
    assert "livedrummer/_services/cli/__init__.py" in names
    assert "livedrummer/_services/bench/jack_ref.c" in names
    assert "livedrummer/_data/kits/rock5.toml" in names
    assert not [n for n in names if "__pycache__" in n]
    entry = next(n for n in names if n.endswith("entry_points.txt"))
    assert (
        "livedrummer = livedrummer._services.cli:main"
        in zipfile.ZipFile(wheel).read(entry).decode()
    )


#: The environment of the installed runs: no PYTHONPATH, which could lead back to a checkout.
CLEAN_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def run_installed(env: Path, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(env / "bin" / "livedrummer"), *args],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=cwd,
        env=CLEAN_ENV,
    )


def test_the_installed_command_works_without_the_checkout(installed: Path, tmp_path: Path) -> None:
    probe = subprocess.run(
        [str(installed / "bin" / "python"), "-c", "import services"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=CLEAN_ENV,
    )
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
