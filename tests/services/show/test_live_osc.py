"""OSC show control: ``up --demo --headless --osc PORT`` steered from the test's own client.

The test sends real OSC datagrams over loopback UDP to ``up``'s port and reads the reply to
``/livedrummer/state`` on its own socket, then checks the frames the display recorded
(frames.jsonl and the PNGs): the camera cut changes the picture, a blackout draws black
frames and the picture comes back, a preset and a parameter reach the synth, and bad
messages are counted while the show goes on.
"""

from __future__ import annotations

import json
import socket
import struct
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

from services.show.osc import decode, encode
from tests.services.cli.test_live_up import launch, wait_running


def read_png(path: Path) -> np.ndarray:
    """An RGB frame as services.display.png writes it (one IDAT, filter 0 on every row)."""
    data = path.read_bytes()
    w, h = struct.unpack(">II", data[16:24])
    at = data.index(b"IDAT")
    size = struct.unpack(">I", data[at - 4 : at])[0]
    rows = np.frombuffer(zlib.decompress(data[at + 4 : at + 4 + size]), np.uint8)
    return rows.reshape(h, 1 + 3 * w)[:, 1:].reshape(h, w, 3)


class Frames:
    """The display's frames.jsonl, read as it grows."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.rows: list[dict[str, object]] = []

    def read(self) -> list[dict[str, object]]:
        path = self.folder / "frames.jsonl"
        if path.exists():
            lines = path.read_text().splitlines()
            self.rows = [json.loads(x) for x in lines if x.endswith("}")]
        return self.rows

    def wait(self, test: object, what: str, timeout: float = 30.0) -> dict[str, object]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for row in self.read():
                if test(row):  # type: ignore[operator]
                    return row
            time.sleep(0.05)  # polling a file another process writes
        raise AssertionError(f"no frame {what} in {len(self.rows)} frames")

    def png(self, row: dict[str, object]) -> np.ndarray:
        return read_png(self.folder / f"frame_{int(row['frame']):06d}.png")  # type: ignore[call-overload]


def state(client: socket.socket, port: int) -> dict[str, object]:
    client.sendto(encode("/livedrummer/state", ()), ("127.0.0.1", port))
    data, _ = client.recvfrom(65536)
    ((address, args),) = decode(data)
    assert address == "/livedrummer/state"
    return dict(zip(args[0::2], args[1::2], strict=True))  # type: ignore[arg-type]


def test_up_is_steered_over_osc(gl_ok: None, tmp_path: Path) -> None:
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    cues = tmp_path / "cues.toml"
    cues.write_text(
        '[[cue]]\nname = "outro"\npreset = "relaxed"\ncamera = "overhead"\n'
        "[cue.params]\ntwist_fraction = 0.1\n"
    )
    proc = launch(
        tmp_path, "--seconds", "60", "--osc", str(port), "--png", "--fps", "10", "--cues", str(cues)
    )
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.bind(("127.0.0.1", 0))
    client.settimeout(5.0)
    frames = Frames(tmp_path / "frames")
    try:
        wait_running(proc)
        first = frames.wait(lambda r: r.get("pose_s") is not None, "with the drummer", 60.0)

        before = state(client, port)
        assert before["preset"] == "neutral" and before["camera"] == "stage"
        assert before["blackout"] == 0 and before["param/amplitude_gain"] == pytest.approx(1.0)
        assert "missing" not in before and {"playing", "onsets", "frames"} <= set(before)

        # garbage, an unknown address and a bad argument: counted, the show goes on
        client.sendto(b"not osc at all", ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/nosuch", (1,)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/camera", ("zoom",)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/param/head_amplitude_deg", (99.0,)), ("127.0.0.1", port))

        client.sendto(encode("/livedrummer/camera/cut", ("front",)), ("127.0.0.1", port))
        cut = frames.wait(lambda r: r.get("camera") == "front", "from the front camera")
        assert int(cut["frame"]) > int(first["frame"])  # type: ignore[call-overload]
        stage_png = frames.png(frames.rows[int(cut["frame"]) - 1])  # type: ignore[call-overload]
        assert np.abs(frames.png(cut).astype(int) - stage_png.astype(int)).mean() > 5.0, (
            "the cut must change the picture"
        )

        client.sendto(encode("/livedrummer/preset", ("energetic",)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/param/head_amplitude_deg", (12.5,)), ("127.0.0.1", port))
        client.sendto(encode("/livedrummer/blackout", (1,)), ("127.0.0.1", port))
        black = frames.wait(lambda r: r.get("dark") == 1.0, "black")
        assert frames.png(black).max() <= 1, "a blacked-out frame is black"
        during = state(client, port)
        assert during["blackout"] == 1 and during["preset"] == "energetic"
        assert during["param/head_amplitude_deg"] == pytest.approx(12.5)
        assert during["param/amplitude_gain"] == pytest.approx(1.3)  # energetic's

        client.sendto(encode("/livedrummer/blackout", (0,)), ("127.0.0.1", port))
        back = frames.wait(lambda r: r.get("dark") == 0.0 and r["frame"] > black["frame"],  # type: ignore[operator]
                           "back from black")  # fmt: skip
        lit = frames.png(cut).mean()
        assert frames.png(back).mean() > 0.8 * lit > 5, "the picture comes back after the blackout"
        assert state(client, port)["camera"] == "front"
        client.sendto(encode("/livedrummer/cue", ("outro",)), ("127.0.0.1", port))
        frames.wait(lambda r: r.get("camera") == "overhead", "from the cue's camera")
        after = state(client, port)
        assert after["preset"] == "relaxed" and after["camera"] == "overhead"
        assert after["param/twist_fraction"] == pytest.approx(0.1)
    finally:
        proc.terminate()
        out, _ = proc.communicate(timeout=60)
        client.close()
    assert proc.returncode == 0, out[-3000:]
    # each kind of bad message is logged once, where it was dropped
    assert out.count("up OSC port: dropped a bad message (packet)") == 1, out[-3000:]
    assert out.count("up OSC port: dropped a bad message (address)") == 1
    assert out.count("display OSC port: dropped a bad message (argument)") == 1
    assert out.count("synth OSC port: dropped a bad message (argument)") == 1


def test_only_loopback_and_allowed_senders_steer_and_bad_input_is_counted() -> None:
    import logging

    from services.show.osc import SYNTH_ADDRESSES, OscEndpoint

    log = logging.getLogger("test")
    for allow, accepted in (((), 0), (("127.0.0.2",), 1)):
        end = OscEndpoint(0, SYNTH_ADDRESSES, "synth", log, allow)
        other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        other.bind(("127.0.0.2", 0))
        try:
            other.sendto(encode("/livedrummer/preset", ("relaxed",)), ("127.0.0.1", end.port))
            deadline = time.monotonic() + 2.0
            got = []
            while time.monotonic() < deadline and not (got or end.bad.total):
                got += end.take()
            assert len(got) == accepted
            assert end.bad.counts.get("sender", 0) == 1 - accepted
        finally:
            other.close()
            end.stop()


def test_the_stage_moves_cuts_and_fades() -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.live.stage import Stage, camera_name

    assert camera_name("front") == "front" and camera_name(2.0) == "front"
    with pytest.raises(ValueError, match="expected one of stage"):
        camera_name(9)
    stage = Stage(load_kit("rock5"), "stage", fade_s=0.5, move_s=1.0)
    start = stage.view(0.0)
    stage.set_camera(3, 10.0)
    assert stage.camera == "drummer" and stage.view(10.0).eye == start.eye
    assert stage.view(10.5).eye != start.eye and stage.view(11.0) == stage.cameras["drummer"]
    stage.set_camera("back", 20.0, cut=True)
    assert stage.view(20.0) == stage.cameras["back"]
    stage.set_blackout(True, 30.0)
    assert stage.darkness(30.0) == 0.0 and stage.darkness(30.25) == pytest.approx(0.5)
    assert stage.darkness(30.5) == 1.0
    stage.set_blackout(False, 30.6)
    assert stage.darkness(31.1) == 0.0
