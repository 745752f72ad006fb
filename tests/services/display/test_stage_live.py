"""A live stage (``up --stage``): three performers, each driving only its own drummer.

End to end with real parts: ``livedrummer up --stage`` runs as a user runs it, on a real
``jackd -d dummy``: two performers play virtual MIDI ports the test plays into (JACK), the
third is a remote site (an input daemon in the test, on a clock 250 ms ahead, playing the
demo groove) reached through the jitter relay and clock-exchange proxy of
:mod:`services.bench._jitter` on loopback, so its local input daemon runs with
``--remote-control``. Performer A plays only the snare, B only the high tom: the frames log
of the one stage display must show A's contacts only on A's drummer and B's only on B's, the
remote groove on C's, every stream without a loss; a recorded frame shows three drummers
side by side in the recorded video. When B's synth is killed, it is restarted alone: A's
and C's streams lose nothing and A's drummer keeps moving meanwhile. Also the ``source`` syntax of a stage file and the display's per-stream
checks (sequence gaps per performer, a pose of the wrong performer refused) on real sockets.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import zmq

from livedrummer.stage.source import LiveSource, parse_source
from livedrummer.stage.stagefile import StageError, load_stage


def test_a_source_is_parsed_and_a_bad_one_is_one_line_naming_the_performer(
    tmp_path: Path,
) -> None:
    assert parse_source("virtual:pads").input_argv() == ["--virtual", "pads"]
    assert parse_source("midi:TD-17").opens_midi
    remote = parse_source("remote:tcp://10.0.0.2:5710,control=tcp://10.0.0.2:5711")
    assert remote == LiveSource("remote", "tcp://10.0.0.2:5710", "tcp://10.0.0.2:5711")
    assert remote.input_argv() == [
        "--remote",
        "tcp://10.0.0.2:5710",
        "--remote-control",
        "tcp://10.0.0.2:5711",
    ]
    assert parse_source("file:a.mid", tmp_path).value == str(tmp_path / "a.mid")
    for bad, why in (
        ("pads", "KIND:VALUE"),
        ("remote:host:5710", "tcp://HOST:PORT"),
        ("virtual:pads,control=tcp://a:1", "only remote"),
        ("remote:tcp://a:1,control=b", "control="),
        ("midi:", "nothing after"),
    ):
        with pytest.raises(ValueError, match=why):
            parse_source(bad)
    path = tmp_path / "s.toml"
    path.write_text('[[performer]]\nid = "x"\nsource = "remote:nowhere"\n')
    with pytest.raises(StageError, match=r"s\.toml: \[performer 'x'\] source: .*tcp://HOST:PORT"):
        load_stage(path)
    path.write_text('[[performer]]\nid = "x"\nfile = "a.mid"\n')
    with pytest.raises(StageError, match="no performer has a live source"):
        load_stage(path).live()
    from services.cli import main

    assert main(["up", "--stage", str(path), "--headless"]) == 2  # one line, nothing started


def _pose_message(performer: int, seq: int, t: float, n_pieces: int) -> list[bytes]:
    from livedrummer.body.pose import pose_dtype
    from livedrummer.protocol import Kind, Message, Pose, PoseFormat, Stream, encode

    rows = np.zeros(4, pose_dtype(n_pieces))
    rows["time_s"] = np.arange(4) / 240.0
    rows["rotation"][..., 3] = 1.0
    msg = Message(Kind.POSE, Pose(t, rows), performer, seq, t, Stream.POSES)
    return encode(msg, PoseFormat.from_dtype(rows.dtype))


def test_each_stream_keeps_its_own_sequence_and_refuses_another_performer() -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.stage.formation import Placement
    from services.display.live import MonotonicFrameClock
    from services.display.stage_live import StageConfig, StageDisplay, StagePerformer

    kit = load_kit("rock5")
    n = len(kit.pieces)
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    pubs = [ctx.socket(zmq.PUB) for _ in range(2)]
    eps = [f"tcp://127.0.0.1:{s.bind_to_random_port('tcp://127.0.0.1')}" for s in pubs]
    who = [
        StagePerformer(name, k + 3, ep, kit, Placement(2.0 * k, 0.0, 0.0))
        for k, (name, ep) in enumerate(zip("ab", eps, strict=True))
    ]
    clock = MonotonicFrameClock()
    display = StageDisplay(who, StageConfig(fps=50, render=False, frames=40), clock, ctx)
    display.start()
    stop = threading.Event()
    thread = threading.Thread(target=display.run, args=(stop,))
    thread.start()
    try:
        time.sleep(0.3)  # subscriptions in
        now = clock.now()
        for seq in (0, 1, 2, 5, 6):  # a: 3 and 4 lost
            pubs[0].send_multipart(_pose_message(3, seq, now + seq * 0.01, n))
        for seq in range(4):  # b: in order, one pose claiming to be performer 3's, a restart
            pubs[1].send_multipart(_pose_message(4, seq, now + seq * 0.01, n))
        pubs[1].send_multipart(_pose_message(3, 7, now, n))
        pubs[1].send_multipart(_pose_message(4, 1, now + 0.05, n))  # b's synth restarted
        thread.join(10)
    finally:
        stop.set()
        thread.join(5)
        for s in pubs:
            s.close(0)
        ctx.term()
    s = display.summary()["performers"]
    a, b = s["a"], s["b"]
    assert (a["pose_messages"], a["missing"], a["bad"], a["restarts"]) == (5, 2, 0, 0), s
    assert (b["pose_messages"], b["missing"], b["bad"], b["restarts"]) == (5, 0, 1, 1), s


def test_the_onsets_and_controls_a_synth_forwards_are_numbered_not_bad() -> None:
    """A synth's pose stream also carries SHOWN_ONSET and SHOWN_CONTROL (for the sound): the
    stage display counts their numbers (no false loss) and takes neither for a bad message."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.protocol import Kind, Message, Stream, encode
    from livedrummer.stage.formation import Placement
    from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE
    from services.display.live import MonotonicFrameClock
    from services.display.stage_live import StageConfig, StageDisplay, StagePerformer

    kit = load_kit("rock5")
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    pub = ctx.socket(zmq.PUB)
    ep = f"tcp://127.0.0.1:{pub.bind_to_random_port('tcp://127.0.0.1')}"
    who = [StagePerformer("a", 3, ep, kit, Placement(0.0, 0.0, 0.0))]
    clock = MonotonicFrameClock()
    display = StageDisplay(who, StageConfig(fps=50, render=False, frames=30), clock, ctx)
    display.start()
    stop = threading.Event()
    thread = threading.Thread(target=display.run, args=(stop,))
    thread.start()
    try:
        time.sleep(0.3)  # subscriptions in
        now = clock.now()
        onset, control = np.zeros(1, ONSET_DTYPE), np.zeros(1, CONTROL_DTYPE)
        onset["velocity"], onset["time_s"], control["time_s"] = 90, now, now
        pub.send_multipart(_pose_message(3, 0, now, len(kit.pieces)))
        pub.send_multipart(encode(Message(Kind.SHOWN_ONSET, onset, 3, 1, now, Stream.POSES)))
        pub.send_multipart(encode(Message(Kind.SHOWN_CONTROL, control, 3, 2, now, Stream.POSES)))
        pub.send_multipart(_pose_message(3, 3, now + 0.01, len(kit.pieces)))
        thread.join(10)
    finally:
        stop.set()
        thread.join(5)
        pub.close(0)
        ctx.term()
    a = display.summary()["performers"]["a"]
    assert (a["pose_messages"], a["missing"], a["bad"], a["restarts"]) == (2, 0, 0, 0), a


rtmidi = pytest.importorskip("rtmidi")


def _synth_pid(pub_port: int) -> int:
    """The pid of the synth process publishing on ``pub_port`` (started by ``up --stage``)."""
    for proc in Path("/proc").iterdir():
        try:
            argv = (proc / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        if b"synth" in argv and f"tcp://127.0.0.1:{pub_port}".encode() in argv:
            return int(proc.name)
    raise AssertionError(f"no synth publishing on {pub_port}")


def _newest(frames: Path, who: str) -> float:
    """The newest pose time of performer ``who`` in the frames log so far."""
    path = frames / "frames.jsonl"
    if not path.exists():
        return -1.0
    newest = -1.0
    for line in path.read_text().splitlines():
        if line.endswith("}"):
            for p in json.loads(line)["performers"]:
                if p["id"] == who and p["newest_s"] is not None:
                    newest = max(newest, p["newest_s"])
    return newest


@pytest.mark.usefixtures("gl_ok")
def test_up_stage_puts_two_local_kits_and_a_remote_site_on_one_stage(
    jack_server: str, tmp_path: Path
) -> None:
    from livedrummer.midi.notemap import load_note_map
    from services.bench._jitter import AheadClock, control_proxy, jitter_relay
    from services.cli.files import DEMO_MAP, demo_groove
    from services.input.daemon import DaemonConfig, InputDaemon
    from services.input.fileplayer import FileSource
    from tests.services.show.test_show_rig import player, wait_port

    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    remote_clock = AheadClock(0.250)
    source = FileSource(demo_groove(), remote_clock, load_note_map(DEMO_MAP), loop=True)
    source.load()
    any_port = "tcp://127.0.0.1:*"
    site = InputDaemon(
        source,
        DaemonConfig(pub=any_port, control=any_port, journal=False, wait_subscribers=1),
        remote_clock,
        ctx,
    )
    eps = site.start()
    stop = threading.Event()
    relay_at: list[str] = []
    proxy_at: list[str] = []
    threads = [
        threading.Thread(target=jitter_relay, args=(ctx, eps["pub"], stop, relay_at)),
        threading.Thread(target=control_proxy, args=(ctx, eps["control"], stop, proxy_at)),
        threading.Thread(target=site.run, args=(stop,)),
    ]
    for t in threads:
        t.start()
    while not relay_at or not proxy_at:
        time.sleep(0.01)
    stage = tmp_path / "stage.toml"
    stage.write_text(
        '[formation]\nshape = "line"\nspacing = 4.0\n\n'
        '[[performer]]\nid = "a"\nsource = "virtual:padsA"\n\n'
        '[[performer]]\nid = "b"\nsource = "virtual:padsB"\npreset = "energetic"\n\n'
        f'[[performer]]\nid = "c"\nsource = "remote:{relay_at[0]},control={proxy_at[0]}"\n'
    )
    frames = tmp_path / "frames"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    up = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "up",
            "--stage",
            str(stage),
            "--api",
            "jack",
            "--headless",
            "--video",
            str(tmp_path / "stage.mp4"),
            "--frames-dir",
            str(frames),
            "--fps",
            "10",
            "--size",
            "330x150",
            "--camera",
            "front",
            "--port-base",
            "7300",
            "--no-journal",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert up.stdout is not None
        deadline = time.monotonic() + 120
        while "display running" not in (line := up.stdout.readline()):
            assert line and time.monotonic() < deadline, up.stderr.read() if up.stderr else ""
        outs = [player(wait_port(name)) for name in ("padsA", "padsB")]

        def play(hits: int) -> None:  # A only the snare, B only the high tom, 4 a second
            for _ in range(hits):
                outs[0].send_message([0x99, 38, 110])
                outs[1].send_message([0x99, 48, 110])
                time.sleep(0.25)

        play(8)
        killed_at = time.monotonic()  # B's synth dies: only B's drummer may stop
        os.kill(_synth_pid(7300 + 20 + 10), signal.SIGKILL)
        deadline = time.monotonic() + 60
        while _newest(frames, "b") < killed_at + 0.5:  # until B's restarted synth is seen
            assert time.monotonic() < deadline, "B's synth did not come back"
            play(1)
        play(8)
        for out in outs:
            out.close_port()
        time.sleep(1.0)  # the last hits shown
    finally:
        up.send_signal(signal.SIGTERM)
        _, err = up.communicate(timeout=60)
        stop.set()
        for t in threads:
            t.join(10)
        site.shutdown()
        ctx.term()
    assert up.returncode == 0, err[-2000:]
    log = [json.loads(line) for line in (frames / "frames.jsonl").read_text().splitlines()]
    lit: dict[str, set[str]] = {"a": set(), "b": set(), "c": set()}
    for record in log:
        for p in record["performers"]:
            lit[p["id"]].update(p["lit"])
    # each performer's notes on its own drummer, and no other's
    assert lit["a"] == {"snare"}, (lit, err[-1500:])
    assert lit["b"] == {"tom1"}, lit
    assert len(lit["c"]) >= 2, lit  # the remote groove: kick, snare, hi-hat ...
    # every stream drawn; A's and C's lost nothing while B's synth was restarted, alone
    for name, lost in (("a", "0"), ("b", r"\d+"), ("c", "0")):
        restarts = "1" if name == "b" else "0"
        assert re.search(
            rf"{name}: [1-9]\d* pose samples, {lost} lost, 0 bad, {restarts} restarts", err
        ), err[-1500:]
    assert "up: stopped (1 restarts)" in err, err[-1500:]
    # while B's stream was down, A's drummer kept getting poses; B drew its hits again after
    after = [r for r in log if r["render_s"] > killed_at + 0.2]  # what was in flight drawn
    b_at_kill = after[0]["performers"][1]["newest_s"]
    outage = []
    for r in after:
        if r["performers"][1]["newest_s"] != b_at_kill:
            break  # B's restarted synth is seen
        outage.append(r)
    a_newest = [r["performers"][0]["newest_s"] for r in outage]
    assert len(outage) >= 3 and a_newest[-1] - a_newest[0] > 0.2, (len(outage), a_newest)
    back = {
        x
        for r in log
        if r["render_s"] > killed_at + 0.5 and r["performers"][1]["newest_s"] > b_at_kill
        for x in r["performers"][1]["lit"]
    }
    assert back == {"tom1"}, back
    import av

    with av.open(str(tmp_path / "stage.mp4")) as c:
        pictures = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
    assert len(pictures) >= 20, len(pictures)  # recorded on show time
    img = pictures[-1].astype(int)
    seen = img.sum(axis=2) > 120  # drummers and kits under their spots, not the dark stage
    thirds = [int(seen[:, k * 110 : (k + 1) * 110].sum()) for k in range(3)]
    assert min(thirds) > 100, thirds  # three drummers side by side


@pytest.mark.usefixtures("gl_ok")
def test_one_pass_depth_tested_drawing_is_the_offline_merge_by_depth(tmp_path: Path) -> None:
    """The stage painter (live and ``render --stage``) draws its drummers into one framebuffer;
    drawing each into its own and keeping per pixel the nearest: the same picture."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.render.body_scene import BODY_SKELETON
    from livedrummer.render.kitmesh import build_kit_mesh
    from livedrummer.stage.formation import Formation, place
    from livedrummer.stage.layout import cell_neighbours
    from services.display.context import headless_context
    from services.display.renderer import Renderer
    from services.display.stage_export import StagePainter, group_camera_for, local_camera
    from services.display.stage_live import StagePerformer

    kit = load_kit("rock5")
    spots = place(Formation("arc", radius=4.0, facing="center"), 3)  # overlapping kits
    who = [StagePerformer(f"p{k}", k, "tcp://127.0.0.1:1", kit, s) for k, s in enumerate(spots)]
    w, h = 240, 136
    ctx = headless_context()
    try:
        painter = StagePainter(ctx, who, (w, h), "front")
        painter.draw([None, None, None])
        live = painter.read_rgba().astype(int)
        world = group_camera_for(kit, spots, "front", w / h)
        colours, depths = [], []
        renderers = [
            Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, (w, h), samples=0, offscreen=False)
            for _ in spots
        ]
        cells = cell_neighbours(spots, [r.pool_centre() for r in renderers])
        for s, r, cell in zip(spots, renderers, cells, strict=True):
            r.floor_cell_others = cell
            fbo = ctx.framebuffer(
                color_attachments=[ctx.texture((w, h), 4)],
                depth_attachment=ctx.depth_texture((w, h)),
            )
            r.draw(None, local_camera(world, s), target=fbo)
            colours.append(np.frombuffer(fbo.read(components=4), np.uint8).reshape(h, w, 4))
            depths.append(
                np.frombuffer(
                    fbo.read(components=1, attachment=-1, dtype="f4"), np.float32
                ).reshape(h, w)
            )
        nearest = np.argmin(np.stack(depths), axis=0)
        offline = np.take_along_axis(np.stack(colours), nearest[None, :, :, None], 0)[0]
        offline = offline.astype(int)
    finally:
        ctx.release()
    drawn = live[..., :3].sum(axis=2) > 60
    assert drawn.mean() > 0.02  # kits on the stage, not an empty frame
    differ = np.abs(live[..., :3] - offline[..., :3]).max(axis=2) > 3
    assert differ.mean() < 0.002, differ.mean()  # depth ties at most


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed")
def test_the_stage_display_draws_in_a_window_under_xvfb(tmp_path: Path) -> None:
    stage = tmp_path / "s.toml"
    stage.write_text(
        '[[performer]]\nid = "a"\nsource = "virtual:a"\n\n'
        '[[performer]]\nid = "b"\nsource = "midi:TD"\n'
    )
    run = subprocess.run(
        [
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 640x360x24",
            sys.executable,
            "-m",
            "services",
            "display",
            "--live",
            "--stage",
            str(stage),
            "--sub",
            "tcp://127.0.0.1:1,tcp://127.0.0.1:2",
            "--size",
            "320x180",
            "--max-frames",
            "6",
            "--fps",
            "30",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert "display: 6 stage frames; a: 0 pose samples" in run.stderr, run.stderr
    short = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "display",
            "--live",
            "--stage",
            str(stage),
            "--sub",
            "tcp://127.0.0.1:1",
            "--headless",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert short.returncode == 2 and "1 endpoints for 2 live performers" in short.stderr
    assert short.stderr.strip().count("\n") == 0


def test_a_stage_performers_map_is_resolved_once_for_its_input_and_synths(
    tmp_path: Path, write_midi: Callable[..., Path]
) -> None:
    # a file source whose notes General MIDI knows and the Roland map does not: map auto was
    # the file's best map in the input daemon and roland-td in the synth
    import mido

    from livedrummer.live.settings import Delay, ShowSettings
    from livedrummer.midi.notemap import bundled_note_maps
    from livedrummer.midi.smf import read_midi_file
    from services.cli import build_parser
    from services.cli.up_stage import stage_specs

    notes = [35, 60, 61, 62, 63, 64, 38, 42] * 4
    groove = write_midi(
        [
            m
            for n in notes
            for m in (
                mido.Message("note_on", channel=9, note=n, velocity=100, time=120),
                mido.Message("note_off", channel=9, note=n, time=0),
            )
        ],
        name="congas.mid",
    )
    best = read_midi_file(groove, bundled_note_maps()).map_name
    assert best != "roland-td"
    stage = tmp_path / "stage.toml"
    stage.write_text(
        '[ensemble]\ncopies = 2\n\n[[performer]]\nid = "file"\n'
        f'source = "file:{groove.name}"\n\n[[performer]]\nid = "kit"\n'
        'source = "virtual:pads"\nkit = "rock5-left"\n'
    )
    argv = ["up", "--stage", str(stage), "--headless", "--delay-ms", "60", "--lookahead-ms", "20"]
    args = build_parser(argv).parse_args(argv)
    folder = tmp_path / "settings"
    folder.mkdir()
    specs = stage_specs(args, stage, Delay(0.020, 0.060), folder)
    given: dict[str, set[str]] = {}
    synths: list[str] = []
    for spec in specs:
        if spec.name == "display":
            shown = spec.argv[spec.argv.index("--settings") + 1].split(",")
            continue
        if spec.name.startswith("synth-"):
            synths.append(spec.argv[spec.argv.index("--settings") + 1])
        assert not {"--map", "--kit", "--avatar", "--delay-ms"} & set(spec.argv), spec.argv
        performer = spec.name.split("-", 1)[1].split(".")[0]
        given.setdefault(performer, set()).add(spec.argv[spec.argv.index("--settings") + 1])
    # one file per performer, for its input daemon and both copies' synths
    assert set(given) == {"file", "kit"} and all(len(v) == 1 for v in given.values()), given
    played = {who: ShowSettings.load(Path(next(iter(f)))) for who, f in given.items()}
    assert (played["file"].note_map, played["file"].kit) == (best, "rock5")
    assert (played["kit"].note_map, played["kit"].kit) == ("roland-td", "rock5-left")
    assert {s.delay for s in played.values()} == {Delay(0.020, 0.060)}
    # the stage display draws each drummer (in --sub's order) with its synth's settings
    assert shown == synths and len(shown) == 4, (shown, synths)
