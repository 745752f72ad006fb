"""Render benchmark: ms per frame headless, with and without read-back, and export speed.

Draws the demo groove as the body model performs it (optimal sticking), from the ``stage``
camera; ``body`` is the time to sample the body's poses and map them to scene frames (per
frame, vectorized over all frames); ``avatar`` the time to generate the built-in character
(:func:`livedrummer.avatar.character.build_character`, median of 5), which every renderer
draws and skins on the GPU.
``draw`` is draw + ``glFinish`` (what a window pays before swapping); ``draw+read`` adds the
RGBA read-back of the frame into numpy, ``draw+i420`` the GPU conversion to YUV 4:2:0 and its
read-back (what export pays before encoding); ``pipelined`` issues all the frames' draws and
waits once at the end (the frame rate a GPU sustains when nothing stalls it on a finish).
Export speed is the whole ``livedrummer render`` job (audio mix, render, H.264/AAC encode)
on the first ``--seconds`` of the demo groove, as a multiple of real time. Medians of one run;
``--aa 0,fxaa,4`` measures no anti-aliasing, the FXAA pass and multisampling interleaved frame
by frame (export: the first).

``--compare REV`` times instead the whole ``livedrummer render`` command, start-up included
(a fresh process: imports, the EGL context, the character, the mix, the encode), of the code
at git revision REV (its files extracted by ``git archive`` into a temporary folder, so the
repository is not written to) and of this tree, alternately,
``--rounds`` times each: before, after, before, after ... so both meet the same load; then the
same for ``render --stage`` of ``--stage-drummers`` drummers on a line. It prints each run's
real-time factor (seconds of video over wall seconds; the frame count and length are read
from the command's own summary line, so an old ``render --stage`` that ignored ``--end`` is
still measured right), the medians and their ratio. Last, for each of ``--live-drummers``
(default 1 and 4), the live stage display's drawing capacity at 1280x720 (median ms a frame of
:func:`services.bench.stage.draw_capacity`, in a fresh process per run), alternating the same
way. A revision whose group camera frames the drummers differently draws different pixels:
the live figure compares the code and what it shows together.

``--layer CAMERAS`` times one frame's draw and I420 read-back at 1280x720 with the static layer
(:mod:`services.display.passes.layer`) and without it, alternating frame by frame in one
process (wall and CPU time, all threads: on a machine others share, CPU time is the steadier
figure), and prints the share of the frame the layer redrew.

``--live-window`` times the live window's frame (drawn and shown, the HUD over it) at
1280x720 as it was (into a 4x multisampled or a plain screen) and as it is (off screen
through the layer, FXAA or none, one blit: :meth:`Renderer.present`), alternating frame by
frame in one process, wall and CPU; then the idle window's frame drawn again against held.
Headless: the screen is a framebuffer of renderbuffers, the swap a blit (the resolve).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.avatar.character import build_character
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import pick_camera
from livedrummer.render.kitmesh import build_kit_mesh

from ..cli.files import DEMO_MAP, demo_groove
from ..cli.render import first_seconds, parse_size
from ..display.context import headless_context
from ..display.export import export
from ..display.renderer import Renderer, i420_ok
from ..display.video import VideoSettings


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench render")
    parser.add_argument("--sizes", default="1280x720,1920x1080")
    parser.add_argument("--frames", type=int, default=120, help="frames per measurement")
    parser.add_argument(
        "--aa",
        default="0",
        help="multisample counts or fxaa, e.g. 0,fxaa,4: measured interleaved, "
        "frame by frame, so each is loaded alike (default 0)",
    )
    parser.add_argument("--seconds", type=float, default=20.0, help="export length (0: skip)")
    parser.add_argument("--export-fps", default="30,60")
    parser.add_argument(
        "--compare",
        metavar="REV",
        help="time the whole render command at git revision REV against this "
        "tree, alternating (see the module docstring)",
    )
    parser.add_argument("--rounds", type=int, default=3, help="--compare: runs of each")
    parser.add_argument(
        "--compare-seconds",
        type=float,
        default=6.0,
        help="--compare: seconds of the demo groove rendered",
    )
    parser.add_argument(
        "--stage-drummers",
        type=int,
        default=4,
        help="--compare: drummers of the render --stage run (0: skip)",
    )
    parser.add_argument("--stage-size", default="640x360", help="--compare: render --stage size")
    parser.add_argument(
        "--live-drummers",
        default="1,4",
        help="--compare: live stage drawing capacity for these drummer counts ('': skip)",
    )
    parser.add_argument(
        "--layer",
        metavar="CAMERAS",
        help="draw+i420 ms a frame at 1280x720 (FXAA, shadows, character) with "
        "the static layer and without, alternating frame by frame, for these "
        "cameras (e.g. stage,front); --frames frames each",
    )
    parser.add_argument(
        "--live-window",
        action="store_true",
        help="the live window's draw+present ms a frame at 1280x720, wall and "
        "CPU: into a 4x multisampled screen (before), a plain one, and off "
        "screen through the static layer with FXAA, then one blit (now); "
        "alternating frame by frame, --frames frames each",
    )
    args = parser.parse_args(argv)
    if args.compare:
        return compare(args)
    if args.layer:
        return layer_compare(args.layer.split(","), args.frames)
    if args.live_window:
        return window_compare(args.frames)

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    perf = read_midi_file(demo_groove(), note_map)
    t0 = time.perf_counter()
    body = BodyScene.perform(perf, kit, note_map)
    t1 = time.perf_counter()
    all_times = np.arange(int(perf.duration_s * 60)) / 60.0
    list(body.frames(all_times))
    t2 = time.perf_counter()
    print(
        f"body: perform {t1 - t0:.2f} s for {perf.duration_s:.0f} s of music; frames "
        f"{(t2 - t1) / all_times.size * 1e3:.3f} ms each ({all_times.size} at 60 fps)"
    )
    builds = []
    for _ in range(5):
        t0 = time.perf_counter()
        avatar = build_character()
        builds.append(time.perf_counter() - t0)
    print(
        f"avatar: built-in character {avatar.mesh.vertex_count} vertices, "
        f"{avatar.mesh.triangle_count} triangles, built in "
        f"{statistics.median(builds) * 1e3:.1f} ms"
    )
    ctx = headless_context()
    counts = [v.strip() for v in args.aa.split(",")]  # multisample counts or "fxaa"
    print(f"render: {ctx.info['GL_RENDERER']} ({ctx.info['GL_VERSION']}), aa {args.aa}")
    cam = pick_camera(kit, "stage")
    times = np.arange(args.frames) / 60.0 + 4.0
    frames = list(body.frames(times))
    for text in args.sizes.split(","):
        size = parse_size(text)
        rs = [
            Renderer(
                ctx,
                build_kit_mesh(kit),
                BODY_SKELETON,
                size,
                avatar=avatar,
                samples=0 if aa == "fxaa" else int(aa),
                fxaa=aa == "fxaa",
            )
            for aa in counts
        ]
        for r in rs:
            r.draw(frames[0], cam)
            r.read_rgba()
        draw: list[list[float]] = [[] for _ in rs]
        read: list[list[float]] = [[] for _ in rs]
        i420: list[list[float]] = [[] for _ in rs]
        for f in frames:  # interleaved: every renderer draws this frame before the next
            for k, r in enumerate(rs):
                t0 = time.perf_counter()
                r.draw(f, cam)
                ctx.finish()
                draw[k].append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                r.draw(f, cam)
                r.read_rgba()
                read[k].append(time.perf_counter() - t0)
                if i420_ok(size):
                    t0 = time.perf_counter()
                    r.draw(f, cam)
                    r.read_i420()
                    i420[k].append(time.perf_counter() - t0)
        for k, r in enumerate(rs):
            piped = []
            for _ in range(3):
                t0 = time.perf_counter()
                for f in frames:
                    r.draw(f, cam)
                ctx.finish()
                piped.append((time.perf_counter() - t0) / len(frames))
            d, rd = statistics.median(draw[k]) * 1e3, statistics.median(read[k]) * 1e3
            pd = statistics.median(piped) * 1e3
            yuv = f"   draw+i420 {statistics.median(i420[k]) * 1e3:6.2f} ms" if i420[k] else ""
            print(
                f"  {text:>9} aa {counts[k]:>4}  draw {d:6.2f} ms ({1e3 / d:6.1f} fps)   "
                f"draw+read {rd:6.2f} ms ({1e3 / rd:6.1f} fps){yuv}   "
                f"pipelined {pd:6.3f} ms ({1e3 / pd:7.1f} fps)"
            )
    ctx.release()
    if args.seconds > 0:
        short = first_seconds(perf, args.seconds)
        short_body = BodyScene.perform(short, kit, note_map)
        with tempfile.TemporaryDirectory() as tmp:
            for fps in (int(v) for v in args.export_fps.split(",")):
                settings = VideoSettings(size=(1280, 720), fps=fps)
                report = export(
                    short,
                    short_body,
                    out=Path(tmp) / "bench.mp4",
                    settings=settings,
                    tail_s=0.0,
                    samples=int(counts[0]) if counts[0].isdigit() else 0,
                    fxaa=counts[0] == "fxaa",
                )
                print(
                    f"  export 1280x720 @ {fps} fps: {report.frames} frames in "
                    f"{report.wall_s:.2f} s = {report.realtime:.2f}x real time"
                )
    return 0


def window_compare(count: int) -> int:
    """The live window's frame (character, shadows, the stage camera, the HUD readout) drawn
    and shown at 1280x720, three ways alternating frame by frame in one process: straight into
    a screen-like framebuffer with 4 samples and resolved as a swap does (the window before),
    into a plain one, and as :class:`~services.display.surface.WindowSurface` draws now
    (off screen, FXAA, the static layer, :meth:`Renderer.present`: one blit). Each frame is
    finished before the next is timed; CPU time is the process's, all threads. Then the idle
    window: the same frame (the kit at rest) drawn again each time, against held."""
    from livedrummer.render.hud import hud_image, live_lines

    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(demo_groove(), note_map), kit, note_map)
    avatar = build_character()
    size = (1280, 720)
    ctx = headless_context()
    cam = pick_camera(kit, "stage")
    hud = hud_image(live_lines("playing", "stage", False, False), 2)
    rect = (8, 8, hud.shape[1], hud.shape[0])

    def screen(samples: int) -> Any:
        colour = ctx.renderbuffer(size, 4, samples=samples)
        depth = ctx.depth_renderbuffer(size, samples=samples)
        return ctx.framebuffer(color_attachments=[colour], depth_attachment=depth)

    shown = screen(0)
    ways: dict[str, tuple[Renderer, Any]] = {
        "screen, 4 samples (before)": (
            Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, offscreen=False, avatar=avatar),
            screen(4),
        ),
        "screen, no samples": (
            Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, offscreen=False, avatar=avatar),
            shown,
        ),
        "layer + blit, no AA": (
            Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, avatar=avatar),
            None,
        ),
        "layer + FXAA + blit (now)": (
            Renderer(
                ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, fxaa=True, avatar=avatar
            ),
            None,
        ),
    }
    wall: dict[str, list[float]] = {k: [] for k in ways}
    cpu: dict[str, list[float]] = {k: [] for k in ways}
    frames = list(body.frames(4.0 + np.arange(count + 2) / 30.0))
    for n, frame in enumerate(frames):
        for name, (r, target) in ways.items():
            t0, c0 = time.perf_counter(), time.process_time()
            r.draw(frame, cam, target=target)
            r.draw_overlay(hud, rect, target)
            if target is None:
                r.present(shown)
            elif target is not shown:
                ctx.copy_framebuffer(shown, target)  # the swap's resolve
            ctx.finish()
            if n >= 2:  # the first frames compile shaders and build the layer
                wall[name].append(time.perf_counter() - t0)
                cpu[name].append(time.process_time() - c0)
    print(
        f"live window 1280x720, {count} frames, {ctx.info['GL_RENDERER']}, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    base = statistics.median(cpu[next(iter(ways))])
    for name in ways:
        w, c = statistics.median(wall[name]) * 1e3, statistics.median(cpu[name]) * 1e3
        print(
            f"  {name:<28} wall {w:6.1f} ms ({1e3 / w:5.1f} fps)   CPU {c:6.1f} ms "
            f"({1e3 / c:5.1f} fps)   CPU before/this {base * 1e3 / c:4.2f}x"
        )
    # the idle window (no poses yet: the kit at rest, the same frame each time), the frame
    # drawn again each time (as before) against held (Renderer._held), alternating
    now = ways["layer + FXAA + blit (now)"][0]
    idle: dict[str, list[float]] = {"drawn again": [], "held": []}
    for n in range(count + 2):
        for name in idle:
            if name == "drawn again":
                now._held = None
            c0 = time.process_time()
            now.draw(None, cam)
            now.draw_overlay(hud, rect)
            now.present(shown)
            ctx.finish()
            if n >= 2:
                idle[name].append(time.process_time() - c0)
    figures = ", ".join(f"{k} {statistics.median(v) * 1e3:.1f} ms" for k, v in idle.items())
    print(f"  idle (no poses: the kit at rest), layer + FXAA + blit: CPU a frame {figures}")
    ctx.release()
    return 0


def layer_compare(cameras: list[str], count: int) -> int:
    """``--layer``: the static layer (:mod:`services.display.passes.layer`) against the full
    path, one renderer each, drawing the same frames alternately; medians and the share of the
    frame the layer redrew."""
    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(demo_groove(), note_map), kit, note_map)
    frames = list(body.frames(np.arange(count) / 30.0 + 4.0))
    size = (1280, 720)
    ctx = headless_context()
    print(
        f"layer: {ctx.info['GL_RENDERER']}, 1280x720, FXAA, shadows, character; "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    for name in cameras:
        cam = pick_camera(kit, name)
        rs = [
            Renderer(
                ctx, build_kit_mesh(kit), BODY_SKELETON, size, samples=0, fxaa=True, static_layer=on
            )
            for on in (False, True)
        ]
        took: list[list[float]] = [[], []]
        cpu: list[list[float]] = [[], []]  # all threads' CPU time: steadier on a shared machine
        shares = []
        for r in rs:  # shaders compiled, the layer built
            r.draw(frames[0], cam)
            r.read_i420()
        for f in frames:
            for k, r in enumerate(rs):
                t0, c0 = time.perf_counter(), time.process_time()
                r.draw(f, cam)
                r.read_i420()
                took[k].append(time.perf_counter() - t0)
                cpu[k].append(time.process_time() - c0)
            layer = rs[1].layer
            if layer is not None:
                shares.append(sum(w * h for _x, _y, w, h in layer.last_rects) / (size[0] * size[1]))
        full, cached = (statistics.median(t) * 1e3 for t in took)
        full_cpu, cached_cpu = (statistics.median(t) * 1e3 for t in cpu)
        share = statistics.mean(shares or [1.0])
        print(
            f"  {name:>9}: wall full {full:7.1f} ms  layer {cached:7.1f} ms "
            f"({full / cached:.2f}x)"
            f"   CPU full {full_cpu:7.1f} ms  layer {cached_cpu:7.1f} ms "
            f"({full_cpu / cached_cpu:.2f}x)   redrawn {share:.0%} of the frame"
        )
    ctx.release()
    return 0


_SUMMARY = re.compile(r"(\d+) frames, ([\d.]+) s")
#: ``render -v``'s last line: its own CPU and its workers'. The workers of ``render --jobs``
#: are a fork server's children, which RUSAGE_CHILDREN of this process never sees.
_WORKERS = re.compile(r"render: ([\d.]+) s of CPU here, ([\d.]+) s in \d+ workers")


def compare(args: argparse.Namespace) -> int:
    """``--compare REV``: see the module docstring."""
    here = Path(__file__).resolve().parents[2]
    with tempfile.TemporaryDirectory() as tmp:
        before = Path(tmp) / "before"
        before.mkdir()
        # the revision's files (git archive): nothing is written into the repository itself
        tar = subprocess.run(
            ["git", "-C", str(here), "archive", "--format=tar", args.compare], capture_output=True
        )
        if tar.returncode != 0:
            print(f"bench render: --compare {args.compare}: {tar.stderr.decode().strip()}")
            return 2
        subprocess.run(["tar", "-x", "-C", str(before)], input=tar.stdout, check=True)
        log = ["git", "-C", str(here), "log", "-1", "--format=%h %s", args.compare]
        rev = subprocess.run(log, capture_output=True, text=True).stdout.strip()
        print(f"before: {rev[:90]}\nafter: this tree ({here})")
        print(
            f"load average at start: {os.getloadavg()[0]:.2f} (other processes share the "
            "cores: compare the ratio, not the absolute figures)"
        )
        secs = f"{args.compare_seconds:g}"
        single = ["render", "--end", secs, "--size", "1280x720", "--fps", "30"]
        _alternate(
            "render 1280x720 @ 30 fps, character, shadows, FXAA, --end " + secs,
            [*single, "-o", str(Path(tmp) / "single.mp4")],
            before,
            here,
            args.rounds,
            Path(tmp),
        )
        if args.stage_drummers > 0:
            from .stage import write_part

            # a part as long as --end: a render --stage from before --end was honoured
            # renders the whole part either way
            write_part(Path(tmp) / "part.mid", 8.0, args.compare_seconds, 0.0)
            stage = Path(tmp) / "line.toml"
            performers = "".join(
                f'[[performer]]\nid = "d{k}"\nfile = "part.mid"\nmap = "roland-td"\n\n'
                for k in range(args.stage_drummers)
            )
            stage.write_text('[formation]\nshape = "line"\nspacing = 2.6\n\n' + performers)
            _alternate(
                f"render --stage, {args.stage_drummers} drummers, {args.stage_size}, --end {secs}",
                [
                    "render",
                    "--stage",
                    str(stage),
                    "--end",
                    secs,
                    "--tail",
                    "0",
                    "--size",
                    args.stage_size,
                    "-o",
                    str(Path(tmp) / "stage.mp4"),
                ],
                before,
                here,
                args.rounds,
                Path(tmp),
            )
        for n in (int(v) for v in args.live_drummers.split(",") if v.strip()):
            _alternate_live(n, before, here, args.rounds)
    return 0


_LIVE = (
    "import sys, numpy as np\n"
    "from services.bench.stage import draw_capacity\n"
    "ms = draw_capacity(int(sys.argv[1]), (1280, 720), 26)\n"
    "sys.stdout.write(f'median {float(np.median(ms)):.3f} ms\\n')\n"
)


def _alternate_live(drummers: int, before: Path, after: Path, rounds: int) -> None:
    """The live stage painter's median ms a frame, ``drummers`` drummers at 1280x720, with
    the code of ``before`` then ``after``, ``rounds`` times; then the medians and fps ratio."""
    print(f"live stage display, {drummers} drummer(s), 1280x720, draw + read-back")
    took: dict[str, list[float]] = {"before": [], "after": []}
    for k in range(rounds):
        for label, root in (("before", before), ("after", after)):
            env = {**os.environ, "PYTHONPATH": str(root)}
            run = subprocess.run(
                [sys.executable, "-c", _LIVE, str(drummers)],
                cwd=root,
                env=env,
                capture_output=True,
                text=True,
            )
            found = re.search(r"median ([\d.]+) ms", run.stdout)
            if run.returncode != 0 or found is None:
                print(f"  {label}: failed ({run.returncode}): {run.stderr.strip()[-200:]}")
                continue
            ms = float(found.group(1))
            took[label].append(ms)
            print(f"  round {k + 1} {label:>6}: {ms:.1f} ms a frame = {1000 / ms:.1f} fps")
    if took["before"] and took["after"]:
        b, a = statistics.median(took["before"]), statistics.median(took["after"])
        print(
            f"  median before {1000 / b:.1f} fps, after {1000 / a:.1f} fps: "
            f"after/before {b / a:.2f}"
        )


def _alternate(
    title: str, command: list[str], before: Path, after: Path, rounds: int, cwd: Path
) -> None:
    """Run ``livedrummer COMMAND`` with the code of ``before`` then ``after``, ``rounds`` times,
    and print each real-time factor, the medians and their ratio."""
    print(title)
    factors: dict[str, list[float]] = {"before": [], "after": []}
    cpu: dict[str, list[float]] = {"before": [], "after": []}
    for k in range(rounds):
        for label, root in (("before", before), ("after", after)):
            env = {**os.environ, "PYTHONPATH": str(root)}
            t0, c0 = time.perf_counter(), _children_cpu_s()
            run = subprocess.run(
                [sys.executable, "-m", "services", "-v", *command],
                cwd=cwd,
                env=env,
                capture_output=True,
                text=True,
            )
            wall = time.perf_counter() - t0
            used = _children_cpu_s() - c0
            told = _WORKERS.search(run.stderr)
            if told is not None:  # the workers' CPU, which the children's count leaves out
                used = max(used, float(told.group(1)) + float(told.group(2)))
            found = _SUMMARY.search(run.stdout)
            if run.returncode != 0 or found is None:
                print(f"  {label}: failed ({run.returncode}): {run.stderr.strip()[-200:]}")
                continue
            video_s = float(found.group(2))
            factors[label].append(video_s / wall)
            cpu[label].append(used)
            print(
                f"  round {k + 1} {label:>6}: {found.group(1)} frames, {video_s:.2f} s of "
                f"video in {wall:.2f} s = {video_s / wall:.2f}x real time, "
                f"{used:.1f} CPU s"
            )
    if factors["before"] and factors["after"]:
        b, a = statistics.median(factors["before"]), statistics.median(factors["after"])
        print(f"  median before {b:.2f}x, after {a:.2f}x real time: after/before {a / b:.2f}")
        cb, ca = statistics.median(cpu["before"]), statistics.median(cpu["after"])
        print(
            f"  median CPU before {cb:.1f} s, after {ca:.1f} s: before/after {cb / ca:.2f} "
            "(all threads: the steadier figure where others share the cores)"
        )


def _children_cpu_s() -> float:
    """User and system CPU seconds of this process's finished children, all their threads."""
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime
