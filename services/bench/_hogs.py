"""CPU hogs for benchmarks that measure under load: N busy processes at normal priority.

A hog is a Python process spinning in a loop, started before the measurement and killed
after it; ``hog_levels("0,1x,2x")`` reads a list of counts where ``Nx`` means N times the
machine's cores.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager

SPIN = "while True: pass"


def hog_levels(spec: str) -> list[int]:
    """Counts from "0,1x,2x": plain numbers, or N times the cores with a trailing x (an
    argparse ``type``: a bad list is the option's one-line error)."""
    cores = os.cpu_count() or 1
    try:
        levels = [int(h[:-1]) * cores if h.endswith("x") else int(h) for h in spec.split(",")]
    except ValueError:
        levels = []
    if not levels or min(levels) < 0:
        raise argparse.ArgumentTypeError(f"expected counts like 0,1x,2x (got {spec!r})")
    return levels


@contextmanager
def hogs(n: int) -> Iterator[None]:
    """``n`` CPU-bound processes for the block's duration."""
    procs = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(n)]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait()
