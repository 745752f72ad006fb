"""``bench latency --compare REV [REV ...]``: the same bench run from other commits and this
checkout, alternating, in one run, and each beside this checkout.

Why this shape. A latency figure on a shared machine means little alone: the load changes
from minute to minute. Before/after figures are only comparable when measured alternating,
under the same load. Each other commit is checked out once into a temporary git worktree
(``git worktree add --detach``; nothing to compile: its Python runs with this interpreter
and its installed dependencies), with a ``shared`` link beside it to this checkout's
``../shared``; then the bench runs ``runs`` times from each checkout in turn, the order
turned by one each round (:func:`order`: this, A, B, then A, B, this, ...; with one REV this,
REV, REV, this), each run a child process started in that checkout, so
each commit measures itself with its own code, its own protocol and its own bench (the
other commit's bench may not read this one's messages). The rows each run prints are read
back (the table's layout has stayed the same since the bench was written) and the medians of
the runs are printed side by side with their ratio, one table per REV, and the load average
at the end. The worktrees are removed afterwards, also on an error, Ctrl-C or SIGTERM.

Limits: the other commit must have ``bench latency`` (``services`` or, before the process
layer moved there, ``livedrummer`` as the package run with ``-m``) and accept the options
passed on; a row it does not print is shown as "-". Its own figures are as good as its
bench: a commit whose bench measured differently is compared on what each bench measured.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import numpy as np

from livedrummer.errors import ConfigError

#: one row of the bench's table: label, sent, on the bus, no pose, late, then six p50/p99 pairs
_ROW = re.compile(r"^\s*(\S+(?: \S+)?)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+\|(.*)$")
_ANSWER = re.compile(r"answered in ([\d.]+|-)/([\d.]+|-) ms")
_PAIRS = ("loop", "bus", "pose", "frame", "pose_onset", "pose_bus")

#: what the side-by-side table shows: (key, heading)
SHOWN = (
    ("late", "late"),
    ("no_pose", "no pose"),
    ("answer_p50", "answered p50"),
    ("answer_p99", "answered p99"),
    ("pose_bus_p50", "pose-bus p50"),
    ("pose_bus_p99", "pose-bus p99"),
    ("pose_onset_p99", "pose-onset p99"),
    ("frame_p99", "frame p99"),
)


@contextmanager
def worktree(checkout: Path, rev: str) -> Iterator[Path]:
    """``rev`` checked out in a temporary git worktree of ``checkout`` (removed after)."""
    tmp = Path(tempfile.mkdtemp(prefix="ld-compare-"))
    path = tmp / "rev"
    done = subprocess.run(
        ["git", "-C", str(checkout), "worktree", "add", "--detach", "-q", str(path), rev],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        tmp.rmdir()
        msg = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "git failed"
        raise ConfigError(f"--compare {rev}: cannot check it out: {msg}")
    shared = checkout.parent / "shared"
    if shared.exists():
        (tmp / "shared").symlink_to(shared)
    try:
        yield path
    finally:
        subprocess.run(
            ["git", "-C", str(checkout), "worktree", "remove", "--force", str(path)],
            capture_output=True,
        )
        (tmp / "shared").unlink(missing_ok=True)
        if tmp.exists() and not any(tmp.iterdir()):
            tmp.rmdir()


def bench_argv(checkout: Path) -> list[str]:
    """The command that runs ``bench latency`` from ``checkout`` with this interpreter."""
    package = "services" if (checkout / "services" / "__main__.py").is_file() else "livedrummer"
    return [sys.executable, "-m", package, "bench", "latency"]


def parse(text: str) -> dict[str, dict[str, float]]:
    """The figures of one run's output, by row label (see :data:`SHOWN`)."""
    out: dict[str, dict[str, float]] = {}
    last: dict[str, float] | None = None
    for line in text.splitlines():
        m = _ROW.match(line)
        if m and m.group(1) != "notes/s":
            cells = [c.split() for c in m.group(6).split("|")]
            row = {"late": float(m.group(5)), "no_pose": float(m.group(4))}
            for name, cell in zip(_PAIRS, cells, strict=False):
                if len(cell) == 2 and cell[0] != "-":
                    row[f"{name}_p50"], row[f"{name}_p99"] = float(cell[0]), float(cell[1])
            out[m.group(1)] = last = row
            continue
        a = _ANSWER.search(line)
        if a and last is not None:
            for key, v in (("answer_p50", a.group(1)), ("answer_p99", a.group(2))):
                if v != "-":
                    last[key] = float(v)
    return out


def order(names: list[str], runs: int) -> list[str]:
    """The runs in turn: ``runs`` rounds of ``names``, each round turned one further, so that
    each name goes first (and last) as often as the others in ``len(names)`` rounds."""
    m = len(names)
    return [names[(r + i) % m] for r in range(runs) for i in range(m)]


def run_compare(checkout: Path, revs: list[str], argv: list[str], runs: int) -> int:
    """Run the bench with ``argv`` from each of ``revs`` and ``checkout`` in turn, ``runs``
    times each, echoing every run, then print each REV's medians beside this checkout's."""
    names = ["this", *dict.fromkeys(revs)]
    results: dict[str, list[dict[str, dict[str, float]]]] = {n: [] for n in names}
    signal.signal(signal.SIGTERM, _exit)  # the worktrees are removed on the way out
    with ExitStack() as stack:
        where = {"this": checkout}
        for rev in names[1:]:
            where[rev] = stack.enter_context(worktree(checkout, rev))
        turns = order(names, runs)
        for k, name in enumerate(turns):
            print(f"\n--- run {k + 1} of {len(turns)}: {name} ({where[name]})", flush=True)
            env = {**os.environ, "PYTHONPATH": str(where[name])}
            done = subprocess.run(
                [*bench_argv(where[name]), *argv],
                cwd=where[name],
                env=env,
                capture_output=True,
                text=True,
            )
            print(done.stdout, end="", flush=True)
            if done.returncode != 0:
                tail = done.stderr.strip().splitlines()[-3:]
                print(f"    ({name}: the bench exited {done.returncode}: {' / '.join(tail)})")
            results[name].append(parse(done.stdout))
    for rev in names[1:]:
        print_side_by_side(results, rev)
    return 0


def _exit(signum: int, _frame: object) -> None:
    raise SystemExit(128 + signum)


def _median(runs: list[dict[str, dict[str, float]]], label: str, key: str) -> float:
    vals = [r[label][key] for r in runs if label in r and key in r[label]]
    return float(np.median(vals)) if vals else float("nan")


def print_side_by_side(results: dict[str, list[dict[str, dict[str, float]]]], rev: str) -> None:
    """Medians over the runs of each commit, REV / this (ratio this / REV)."""
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    runs = len(results["this"])
    print(
        f"\n{rev} / this checkout: medians of {runs} alternating runs each (ms; late and no "
        f"pose: notes); load average {load} (1, 5, 15 min)"
    )
    labels = list(dict.fromkeys(label for r in [*results[rev], *results["this"]] for label in r))
    print(f"{'run':>10} | " + " | ".join(f"{head:>22}" for _, head in SHOWN))
    for label in labels:
        cells = []
        for key, _ in SHOWN:
            a, b = _median(results[rev], label, key), _median(results["this"], label, key)
            ratio = f"x{b / a:.2f}" if a > 0 and not np.isnan(b) else "    "
            cells.append(f"{a:6.1f} / {b:6.1f} {ratio:>6}".replace("nan", "  -"))
        print(f"{label:>10} | " + " | ".join(f"{c:>22}" for c in cells), flush=True)
