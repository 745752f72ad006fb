"""A live stage under load: 4 performers at 100 notes/s each, one display drawing all four.

Runs ``livedrummer up --stage`` as a user would, headless, on a stage file of ``--performers``
live performers, each an input daemon playing (``file:``, looped, as if live) a part the bench
writes: ``--rate`` notes a second spread over snare, hi-hat, kick and toms, each performer's
shifted by a fraction of a note so the four do not hit together. Prints each synth's
"answered in" p50/p99 (from its own summary: from an onset's arrival to the first pose
message showing it) and what the stage display drew at ``--size`` (default 1280x720, llvmpipe
where there is no GPU): frames per second actually drawn over the run, and the median and p90
time to draw one frame (N renders into one depth-tested framebuffer), from ``frames.jsonl``;
then the same drawing alone on the machine (:func:`draw_capacity`), without the synths.
One run, figures only, no assertions; the machine's other load counts (every process of the
stage shares its cores).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from ..process.program import program_argv
from ._paths import WORKDIR

NOTES = (38, 42, 36, 42, 48, 42, 45, 42, 38, 46)  # all in the roland-td map


def write_part(path: Path, rate_hz: float, seconds: float, shift: float) -> None:
    """A part of ``rate_hz`` notes a second for ``seconds`` (1 tick = 1 ms)."""
    import mido

    mid = mido.MidiFile(ticks_per_beat=1000)
    track = mido.MidiTrack()
    track.append(mido.MetaMessage("set_tempo", tempo=1_000_000, time=0))
    step = 1000.0 / rate_hz
    last = 0
    for k in range(int(rate_hz * seconds)):
        at = round((k + shift) * step)
        note = NOTES[k % len(NOTES)]
        track.append(mido.Message("note_on", channel=9, note=note, velocity=90, time=at - last))
        track.append(mido.Message("note_off", channel=9, note=note, velocity=0, time=1))
        last = at + 1
    mid.tracks.append(track)
    mid.save(path)


def draw_capacity(performers: int, size: tuple[int, int], frames: int) -> np.ndarray:
    """Milliseconds to draw each of ``frames`` stage frames of ``performers`` drummers (the
    demo groove animated offline, every drummer on its spot of an arc) with the live stage
    display's painter, alone on the machine: what the display could draw without the synths.
    Each frame is finished (and read back, as for a recording) before the next is timed."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.stage.formation import Formation, place

    from ..cli import build_parser
    from ..cli.files import DEMO_MAP, demo_groove, read_performance
    from ..cli.render import body_scene
    from ..display.context import headless_context
    from ..display.stage_export import StagePainter
    from ..display.stage_live import StagePerformer

    args = build_parser(["render"]).parse_args(["render", str(demo_groove())])
    performance, note_map = read_performance(args, demo_groove(), DEMO_MAP, quiet=True)
    kit = load_kit("rock5")
    body = body_scene(args, performance, kit, note_map)
    spots = place(Formation("arc", radius=6.0, facing="center"), performers)
    who = [StagePerformer(f"p{k}", k, "", kit, spot) for k, spot in enumerate(spots)]
    times = 2.0 + np.arange(frames) / 30.0
    ctx = headless_context()
    took = []
    try:
        painter = StagePainter(ctx, who, size, "stage")
        for frame in body.frames(times):
            start = time.perf_counter()
            painter.draw([frame] * performers)
            painter.read_rgba()
            took.append(time.perf_counter() - start)
    finally:
        ctx.release()
    return np.array(took[2:]) * 1000  # the first frames compile shaders


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(prog="livedrummer bench stage", description=__doc__)
    ap.add_argument("--performers", type=int, default=4, help="live performers (default 4)")
    ap.add_argument("--rate", type=float, default=100.0, help="notes/s each (default 100)")
    ap.add_argument("--seconds", type=float, default=20.0, help="run length (default 20)")
    ap.add_argument("--size", default="1280x720", help="display frame size (default 1280x720)")
    ap.add_argument("--fps", type=float, default=30.0, help="display fps asked (default 30)")
    ap.add_argument("--port-base", type=int, default=7500, help="(default 7500)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="bench-stage-") as tmp:
        folder = Path(tmp)
        lines = ['[formation]\nshape = "arc"\nradius = 6.0\nfacing = "center"\n']
        for k in range(args.performers):
            write_part(folder / f"p{k}.mid", args.rate, 10.0, k / args.performers)
            lines.append(
                f'[[performer]]\nid = "p{k}"\nsource = "file:p{k}.mid"\nmap = "roland-td"\n'
            )
        (folder / "stage.toml").write_text("\n".join(lines))
        frames = folder / "frames"
        print(
            f"bench stage: {args.performers} live performers at {args.rate:g} notes/s each, "
            f"display {args.size} at {args.fps:g} fps asked, {args.seconds:g} s"
        )
        err_path = folder / "up.err"
        with err_path.open("w") as err:
            up = subprocess.Popen(
                [
                    *program_argv(
                        "up",
                        "--stage",
                        str(folder / "stage.toml"),
                        "--headless",
                        "--frames-dir",
                        str(frames),
                        "--size",
                        args.size,
                        "--fps",
                        str(args.fps),
                        "--port-base",
                        str(args.port_base),
                        "--no-journal",
                    )
                ],
                stdout=subprocess.PIPE,
                stderr=err,
                text=True,
                cwd=WORKDIR,
                env={**os.environ, "LIVEDRUMMER_HOME": str(folder / "home")},
            )
            assert up.stdout is not None
            while "display running" not in (line := up.stdout.readline()):
                if not line:
                    print(err_path.read_text()[-2000:])
                    return 1
            time.sleep(args.seconds)
            up.send_signal(signal.SIGTERM)
            up.communicate(timeout=120)
        text = err_path.read_text()
        for m in re.finditer(
            r"synth: (\d+) onsets.*answered in ([\d.]+)/([\d.]+) ms p50/p99"
            r".*?(\d+) contacts late",
            text,
        ):
            print(
                f"  synth: {m.group(1)} onsets, answered in p50 {m.group(2)} ms, "
                f"p99 {m.group(3)} ms ({m.group(4)} contacts late)"
            )
        log = [json.loads(x) for x in (frames / "frames.jsonl").read_text().splitlines()]
        drawing = [r for r in log if any(p["pose_s"] is not None for p in r["performers"])]
        if len(drawing) < 2:
            print("  display: fewer than 2 frames with drummers")
            return 1
        span = drawing[-1]["done_s"] - drawing[0]["render_s"]
        took = np.array([r["done_s"] - r["render_s"] for r in drawing]) * 1000
        p50, p90 = np.percentile(took, [50, 90])
        print(
            f"  display: {len(drawing)} frames with {args.performers} drummers in "
            f"{span:.1f} s = {len(drawing) / span:.1f} fps drawn (goal >= 30); "
            f"a frame takes p50 {p50:.0f} ms, p90 {p90:.0f} ms to draw"
        )
        for line in text.splitlines():
            if line.startswith("display:"):
                print(f"  {line}")
    w, h = (int(v) for v in args.size.split("x"))
    alone = draw_capacity(args.performers, (w, h), 32)
    p50 = float(np.median(alone))
    print(
        f"  display alone (no synths running): a {args.size} frame of {args.performers} "
        f"drummers in p50 {p50:.0f} ms, p90 {np.percentile(alone, 90):.0f} ms = "
        f"{1000 / p50:.1f} fps"
    )
    return 0
