"""A remote drummer through a jittery network: intervals kept, clock offset found.

Runs :func:`~services.bench._jitter.remote_session` twice on loopback: a remote site playing
the demo groove on a clock 753.1 ms ahead of ours, its events delayed by 20-60 ms of random
jitter (in order), first received by ``input --remote`` alone (hits stamped on arrival, as
before ``--remote-control``), then with ``--remote-control`` (clock exchanges through a proxy
adding 0-10 ms each way; offset, drift and jitter buffer). Prints per run the error of the
intervals between successive hits against the intervals played (p50/p99/max, from the third
second on), the median delay from the remote hit to its local onset, and, with
``--remote-control``, the offset estimate's error and what the daemon reported. Figures from
one run; no assertions.
"""

from __future__ import annotations

import argparse
import re
import tempfile
from pathlib import Path

import numpy as np

from ._jitter import remote_session

OFFSET_S = 0.7531


def intervals(
    sent: list[float], got: list[float], settle_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """(|interval error| per successive pair in ms from ``settle_s`` on, lag of each hit in s)."""
    n = min(len(sent), len(got))
    s, g = np.array(sent[:n]), np.array(got[:n])
    keep = s >= s[0] + settle_s
    err = 1000 * np.abs(np.diff(g) - np.diff(s))[keep[1:]]
    return err, (g - (s - OFFSET_S))[keep]


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="livedrummer bench remote_timing", description=__doc__)
    ap.add_argument("--seconds", type=float, default=20.0, help="each run (default 20)")
    args = ap.parse_args(argv)
    print(
        f"bench remote_timing: demo groove from a remote clock {1000 * OFFSET_S:.1f} ms "
        f"ahead, 20-60 ms of jitter, {args.seconds:g} s a run"
    )
    with tempfile.TemporaryDirectory() as home:
        for control in (False, True):
            run = remote_session(
                args.seconds,
                control=control,
                offset_s=OFFSET_S,
                home=home,
                err_path=Path(home) / "input.err",
            )
            err, lag = intervals(run.sent, run.got, 3.0)
            p50, p99 = np.percentile(err, [50, 99])
            label = "--remote-control" if control else "stamped on arrival"
            line = (
                f"  {label:>18}: {len(run.got)} of {len(run.sent)} hits; interval error "
                f"p50 {p50:.2f} ms, p99 {p99:.2f} ms, max {err.max():.2f} ms; "
                f"played {1000 * float(np.median(lag)):.1f} ms after the remote hit"
            )
            print(line)
            m = re.search(r"remote clock ([+-][\d.]+) ms \(\+/- ([\d.]+)\).*", run.summary)
            if control and m:
                off = float(m.group(1)) - 1000 * OFFSET_S
                print(f"  {'':>18}  offset estimate error {off:+.3f} ms; daemon: {m.group(0)}")
    return 0
