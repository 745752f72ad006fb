"""``livedrummer relay``: fan a synth's pose stream out to many displays (see
services.relay.service).

Once bound it prints one JSON line on stdout (``{"service": "relay", "pub": ..., "control":
..., "upstream": ...}``), tells a launcher or systemd it is ready, and forwards until Ctrl-C /
SIGTERM; at exit it prints a one-line summary on stderr.
"""

from __future__ import annotations

import argparse
import sys

from .keys import add_curve_options, security_from_args
from .parsing import Subparsers, add_command


def register(sub: Subparsers) -> None:
    from ..relay.service import DEFAULT_CONTROL, DEFAULT_PUB

    p = add_command(sub, "relay", run)
    p.add_argument(
        "--upstream",
        required=True,
        metavar="ENDPOINT",
        help="the pose endpoint of the synth (or of another relay) to forward, "
        "e.g. tcp://10.0.0.5:5720",
    )
    p.add_argument(
        "--upstream-control",
        metavar="ENDPOINT",
        help="its control endpoint: the relay's READY then carries the synth's pose "
        "format and avatar (default: not asked)",
    )
    p.add_argument(
        "--pub", default=DEFAULT_PUB, help=f"where displays subscribe (default {DEFAULT_PUB})"
    )
    p.add_argument(
        "--control",
        default=DEFAULT_CONTROL,
        help=f"HELLO/READY endpoint (default {DEFAULT_CONTROL})",
    )
    add_curve_options(p, server=True, client=True)


def run(args: argparse.Namespace) -> int:
    import zmq

    from livedrummer.timeline.clock import MonotonicClock

    from ..process.service import serve
    from ..relay.service import RelayConfig, RelayService

    config = RelayConfig(
        upstream=args.upstream,
        upstream_control=args.upstream_control,
        pub=args.pub,
        control=args.control,
        security=security_from_args(args),
    )
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    service = RelayService(config, MonotonicClock(), ctx)
    code = serve(service, lambda endpoints: endpoints["pub"])
    s = service.summary()
    print(
        f"relay: {s['messages']} messages ({s['bytes']:,} bytes) forwarded, "
        f"{s['subscriptions']} subscriptions",
        file=sys.stderr,
    )
    return code
