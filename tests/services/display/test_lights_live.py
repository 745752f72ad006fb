"""Show lights changed live: OSC over a real UDP socket into a headless live display (EGL,
llvmpipe), read back from the PNGs it writes.

The display runs in this process with no synth (it draws the kit, no drummer); the test is
the cue desk. A look change shows in the very frame whose log says it was applied (the frame
before is still the old look), switching the four lights off in one bundle leaves only the
ambient, and bad commands are counted while the frames keep coming.
"""

from __future__ import annotations

import socket
import threading
from pathlib import Path

import numpy as np
import zmq
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from livedrummer.kit.lights import LIGHT_NAMES
from livedrummer.kit.loader import load_kit
from livedrummer.render.litshare import lit_share
from services.display.live import LiveConfig, LiveDisplay, MonotonicFrameClock
from services.show.osc import decode, encode
from tests.services.show.test_live_osc import Frames


def _bundle(messages: list[tuple[str, tuple[float, ...]]]) -> bytes:
    b = OscBundleBuilder(IMMEDIATELY)
    for address, args in messages:
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        b.add_content(m.build())  # type: ignore[arg-type]
    return b.build().dgram


def _state(client: socket.socket, port: int) -> dict[str, object]:
    client.sendto(encode("/livedrummer/state", ()), ("127.0.0.1", port))
    data, _ = client.recvfrom(65536)
    ((_, args),) = decode(data)
    return dict(zip(args[0::2], args[1::2], strict=True))  # type: ignore[arg-type]


def test_osc_changes_the_look_and_the_lights_of_the_next_frame(gl_ok: None, tmp_path: Path) -> None:
    ctx: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    kit = load_kit("rock5")
    config = LiveConfig(
        sub="tcp://127.0.0.1:1", fps=10.0, size=(320, 180), camera="front", out=tmp_path, osc_port=0
    )
    display = LiveDisplay(kit, config, MonotonicFrameClock(), ctx)
    endpoints = display.start()
    port = int(endpoints["osc"].rsplit(":", 1)[1])
    stop = threading.Event()
    thread = threading.Thread(target=display.run, args=(stop,), daemon=True)
    thread.start()
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.settimeout(10.0)
    frames = Frames(tmp_path)
    try:
        first = frames.wait(lambda r: r["frame"] == 2, "drawn")
        assert first["look"] == "concert"
        for address, args in (
            ("/livedrummer/light/spot/intensity", (1.0,)),
            ("/livedrummer/light/key/intensity", (99.0,)),
            ("/livedrummer/light/key/color", (1.0, "x", 0.0)),
            ("/livedrummer/light/key/enabled", (2,)),
            ("/livedrummer/look", ("disco",)),
        ):
            client.sendto(encode(address, args), ("127.0.0.1", port))
        assert _state(client, port)["look"] == "concert", "a bad command changes nothing"
        client.sendto(encode("/livedrummer/look", ("neon",)), ("127.0.0.1", port))
        neon = frames.wait(lambda r: r["look"] == "neon", "in the neon look")
        k = int(neon["frame"])  # type: ignore[call-overload]
        before = frames.png(frames.rows[k - 1]).astype(float)
        after = frames.png(neon).astype(float)
        earlier = frames.png(first).astype(float)
        assert frames.rows[k - 1]["look"] == "concert"
        assert np.abs(before - earlier).mean() < 0.5, "the kit alone, unchanged under one look"
        assert np.abs(after - before).mean() > 3.0, "the frame that applied it shows it"
        # neon's key is magenta and its back light violet: blue and red gain on green
        rb = lambda im: (im[..., 0].mean() + im[..., 2].mean()) / (2 * im[..., 1].mean() + 1)  # noqa: E731
        assert rb(after) > 1.2 * rb(before)
        off = _bundle([(f"/livedrummer/light/{n}/enabled", (0,)) for n in LIGHT_NAMES])
        client.sendto(off, ("127.0.0.1", port))
        dark = frames.wait(lambda r: r["look"] == "custom", "with the lights off")
        dark_rgb = frames.png(dark)
        assert lit_share(dark_rgb) < 0.25 * lit_share(after.astype(np.uint8))
        client.sendto(encode("/livedrummer/light/key/enabled", (1,)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/light/key/color", ("#ffffff",)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/light/key/direction", (0.0, 30.0)), ("127.0.0.1", port))
        frames.wait(lambda r: r["frame"] > int(dark["frame"]) + 3, "after the key is back on")  # type: ignore[call-overload]
        lit = frames.png(frames.rows[-1])
        assert lit_share(lit) > 2 * lit_share(dark_rgb), "the key alone lights the kit again"
        assert display.show is not None and display.show.osc is not None
        assert display.show.osc.bad.counts["argument"] == 5
        key = display.show.stage.lights.key
        assert key.enabled and key.color == (1.0, 1.0, 1.0) and key.azimuth_deg == 0.0
        assert key.elevation_deg == 30.0 and key.intensity == 3.0  # neon's, kept while off
    finally:
        stop.set()
        thread.join(10.0)
        client.close()
        ctx.destroy(0)


def test_up_forwards_look_osc_and_bar_cues_light_the_display(gl_ok: None, tmp_path: Path) -> None:
    from tests.services.cli.test_live_up import launch, wait_running

    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    cues = tmp_path / "cues.toml"
    cues.write_text(
        '[[cue]]\nname = "dim"\nbar = 4\n[cue.lights.key]\nenabled = false\n'
        "[cue.lights.fill]\nenabled = false\n[cue.lights.wash]\nenabled = false\n"
    )
    proc = launch(
        tmp_path,
        "--headless",
        "--seconds",
        "14",
        "--png",
        "--fps",
        "10",
        "--osc",
        str(port),
        "--look",
        "studio",
        "--cues",
        str(cues),
    )
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.bind(("127.0.0.1", 0))
    client.settimeout(5.0)
    frames = Frames(tmp_path / "frames")
    try:
        wait_running(proc)
        first = frames.wait(lambda r: r.get("pose_s") is not None, "with the drummer", 60.0)
        assert first["look"] == "studio", "up's --look reaches its display"
        client.sendto(encode("/livedrummer/light/rim/intensity", (-1.0,)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/look", ("neon",)), ("127.0.0.1", port))
        frames.wait(lambda r: r.get("look") == "neon", "in the look sent to up's port")
        assert _state(client, port)["look"] == "neon"
        dim = frames.wait(lambda r: r.get("look") == "custom", "lit by the bar cue", 60.0)
        out, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.terminate()
            proc.communicate(timeout=60)
        client.close()
    assert proc.returncode == 0, out[-3000:]
    rows = frames.read()
    k = int(dim["frame"])  # type: ignore[call-overload]
    assert [name for name, _at, _late in dim.get("cues", [])] == ["bar 4"]  # type: ignore[attr-defined]
    assert rows[k - 1]["look"] == "neon" and all(r["look"] == "custom" for r in rows[k:])
    before, after = frames.png(rows[k - 1]).mean(), frames.png(dim).mean()
    assert after < 0.6 * before, "the key, fill and wash go out on bar 4; the rim stays"
    assert out.count("display OSC port: dropped a bad message (argument)") == 1
