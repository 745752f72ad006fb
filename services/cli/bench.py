"""``livedrummer bench NAME``: run a benchmark module from ``bench/`` and print its figures.

Benchmarks print medians and ratios measured in one run; they never assert on wall time.
Every module ``services/bench/NAME.py`` with a ``main(argv) -> int`` is a benchmark.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil

from .parsing import Subparsers, add_command


def available() -> list[str]:
    from .. import bench

    return sorted(
        m.name for m in pkgutil.iter_modules(bench.__path__) if not m.name.startswith("_")
    )


def register(sub: Subparsers) -> None:
    p = add_command(sub, "bench", run, "run a benchmark and print its figures")
    p.add_argument("name", choices=available(), help="which benchmark")
    p.add_argument("rest", nargs=argparse.REMAINDER, help="options for the benchmark")


def run(args: argparse.Namespace) -> int:
    module = importlib.import_module(f"..bench.{args.name}", __package__)
    code: int = module.main(args.rest)
    return code
