"""OSC benchmark: from an OSC message sent to ``up --osc`` to the first frame that shows it.

Runs ``up --demo --headless --osc PORT`` (frames.jsonl only, no PNGs), waits for the
drummer, then sends ``--commands`` messages, half a second apart: camera cuts alternating
between two viewpoints, and blackouts on and off. Each is stamped with the shared monotonic
clock when sent; the display's frames.jsonl stamps every frame's start (``render_s``) and end
(``done_s``) on the same clock and names its camera and darkness. A message's latency in
frames is k when the k-th frame begun after it is the first to show it (1: the very next
frame); in milliseconds, from the send to the end of that frame. Medians and worst cases.
"""

from __future__ import annotations

import argparse
import json
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ..process.program import program_argv
from ..show.osc import encode
from ._ports import free_port_base


def _wait_frames(path: Path, deadline: float) -> list[dict[str, object]]:
    while time.monotonic() < deadline:
        if path.exists():
            rows = [json.loads(x) for x in path.read_text().splitlines() if x.endswith("}")]
            if any(r.get("pose_s") is not None for r in rows):
                return rows
        time.sleep(0.1)  # polling a file another process writes
    raise SystemExit("bench osc: the display drew no drummer in time")


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="livedrummer bench osc")
    p.add_argument("--commands", type=int, default=20)
    p.add_argument("--fps", type=float, default=30.0)
    args = p.parse_args(argv)
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = int(probe.getsockname()[1])
    probe.close()
    base = free_port_base()
    with tempfile.TemporaryDirectory(prefix="livedrummer-bench-osc-") as tmp:
        out = Path(tmp) / "frames"
        proc = subprocess.Popen(
            [
                *program_argv(),
                "up",
                "--demo",
                "--headless",
                "--osc",
                str(port),
                "--port-base",
                str(base),
                "--frames-dir",
                str(out),
                "--fps",
                str(args.fps),
                "--seconds",
                "600",
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sent: list[tuple[float, str, object]] = []
        want: tuple[str, object]
        try:
            _wait_frames(out / "frames.jsonl", time.monotonic() + 120)
            for k in range(args.commands):
                if k % 2 == 0:
                    cam = ("front", "stage")[(k // 2) % 2]
                    msg, want = encode("/livedrummer/camera/cut", (cam,)), ("camera", cam)
                else:
                    on = (k // 2) % 2 == 0
                    msg, want = encode("/livedrummer/blackout", (int(on),)), ("dark", on)
                t = time.monotonic()
                client.sendto(msg, ("127.0.0.1", port))
                sent.append((t, *want))
                time.sleep(0.5)  # the cue rate of a show, not a handshake
            time.sleep(0.5)
        finally:
            client.close()
            proc.terminate()
            proc.wait(60)
        rows = [
            json.loads(x)
            for x in (out / "frames.jsonl").read_text().splitlines()
            if x.endswith("}")
        ]
    frames, ms = [], []
    for t, field, value in sent:
        after = [r for r in rows if float(r["render_s"]) >= t]
        for k, r in enumerate(after, 1):
            dark = float(r.get("dark", 0.0))
            # a blackout shows from the first frame of its fade, its end from the first
            # frame lighter than black
            shown = (
                r.get("camera") == value
                if field == "camera"
                else (dark > 0.0 if value else dark < 1.0)
            )
            if shown:
                frames.append(k)
                ms.append(1e3 * (float(r["done_s"]) - t))
                break
    if not frames:
        print("bench osc: no change was seen in the frames", file=sys.stderr)
        return 1
    print(
        f"osc -> frame at {args.fps:g} fps: {len(frames)}/{len(sent)} changes seen; "
        f"first frame showing it: median {statistics.median(frames):g}, worst {max(frames)} "
        f"frames after the message; {statistics.median(ms):.1f} ms median, "
        f"{max(ms):.1f} ms worst (send to frame done)"
    )
    return 0
