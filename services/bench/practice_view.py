"""Practice view benchmark: what the teacher and the readout add to a live frame, headless.

On the funk groove of the Groove MIDI Dataset's eval session (if the dataset is beside the
checkout, else the demo groove), at ``--size`` (640x360, the headless practice default): per
frame, ``player`` is the player's frame alone (draw + ``glFinish``); ``off``, ``ghost`` and
``ahead`` are the same frame with :class:`~services.display.practice_view.PracticeView` drawing
over it (the readout only; the ghost's body render, read-back, recolour and blend; the inset's
small scene), with a fresh hit every frame so the readout is repainted each time (its worst
case). The modes take turns frame by frame, so each sees the same load; medians over
``--frames`` frames; the player's pose runs 0.3 s behind the teacher's.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
import zmq

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.practice.teacher import PassTime
from livedrummer.render.body_scene import BodyScene

from ..cli.files import demo_groove
from ..cli.render import parse_size
from ..display.practice_view import PracticeView, TeacherMode
from ..display.surface import HeadlessSurface

FUNK = Path(__file__).resolve().parents[2].parent / "shared/data/groove/drummer1/eval_session"


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(prog="livedrummer bench practice_view")
    p.add_argument("--size", default="640x360")
    p.add_argument("--frames", type=int, default=60)
    args = p.parse_args(argv)
    size = parse_size(args.size)
    note_map = load_note_map("roland-td")
    found = sorted(FUNK.glob("1_funk-groove1_*.mid"))
    source = found[0] if found else demo_groove()
    performance = read_midi_file(source, note_map)
    kit = load_kit("rock5")
    t0 = time.perf_counter()
    body = BodyScene.perform(performance, kit, note_map)
    print(
        f"practice_view {args.size}: {source.name}, teacher animated in "
        f"{time.perf_counter() - t0:.2f} s ({performance.onsets.size} notes)"
    )
    times = np.linspace(1.0, max(1.5, performance.duration_s - 1.0), args.frames)
    frames = list(body.frames(times - 0.3))
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    surface = HeadlessSurface(kit, size, "stage")
    figures: dict[str, list[float]] = {m: [] for m in ("player", "off", "ghost", "ahead")}
    views: dict[str, PracticeView | None] = {"player": None}
    try:
        modes: tuple[TeacherMode, ...] = ("off", "ghost", "ahead")
        for mode in modes:
            made = PracticeView(
                ctx, "tcp://127.0.0.1:9", kit, mode, body if mode != "off" else None, ahead_s=0.5
            )
            made.clock.add(PassTime(0.0, 1.0, 0.0, performance.duration_s))
            views[mode] = made
        for k, (t, frame) in enumerate(zip(times, frames, strict=True)):
            for name, view in views.items():  # interleaved: each mode sees the same load
                if view is not None:
                    view.panel.apply(
                        {
                            "hit": {
                                "piece": "snare",
                                "offset_ms": float(k % 40 - 20),
                                "on_time": True,
                                "streak": k,
                                "accuracy_pct": 90.0,
                            }
                        }
                    )
                t0 = time.perf_counter()
                surface.draw(frame, float(t))
                if view is not None:
                    view.draw(surface, float(t))
                surface.renderer.finish()
                figures[name].append(time.perf_counter() - t0)
    finally:
        for v in views.values():
            if v is not None:
                v.close()
        surface.close()
        ctx.destroy(0)
    base = statistics.median(figures["player"])
    for what, spent in figures.items():
        med = statistics.median(spent)
        extra = "" if what == "player" else f"  (+{1e3 * (med - base):.1f} ms)"
        print(f"  {what:<7} {1e3 * med:7.1f} ms a frame{extra}")
    return 0
