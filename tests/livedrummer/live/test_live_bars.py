"""Bars, live: ``up --demo --headless --osc PORT --cues FILE`` fires the list's ``bar`` cue
once the beat tracker has counted its bar, with no OSC cue sent; the state reply shows it."""

from __future__ import annotations

import socket
import time
from pathlib import Path

import pytest

from tests.services.cli.test_live_up import launch, wait_running
from tests.services.show.test_live_osc import state


def test_up_fires_a_bar_cue_when_the_beat_tracker_counts_its_bar(
    gl_ok: None, tmp_path: Path
) -> None:
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    cues = tmp_path / "cues.toml"
    cues.write_text(
        '[[cue]]\nname = "chorus"\nbar = 4\npreset = "energetic"\n'
        "[cue.params]\nhead_amplitude_deg = 12.5\n"
    )
    proc = launch(
        tmp_path, "--seconds", "60", "--osc", str(port), "--fps", "10", "--cues", str(cues)
    )
    client = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    client.bind(("127.0.0.1", 0))
    client.settimeout(5.0)
    try:
        wait_running(proc)
        first = state(client, port)
        assert first["preset"] == "neutral", "the bar cue waits for its bar"
        seen = [first]
        deadline = time.monotonic() + 40.0
        while seen[-1].get("preset") != "energetic" and time.monotonic() < deadline:
            time.sleep(0.25)  # the demo plays on; the synth counts bars as it hears them
            seen.append(state(client, port))
        fired = seen[-1]
        assert fired.get("preset") == "energetic", f"no bar cue after {len(seen)} polls"
        assert fired["param/head_amplitude_deg"] == pytest.approx(12.5)
        assert int(fired["onsets"]) >= 12  # type: ignore[call-overload]  # bars were heard
    finally:
        proc.terminate()
        out, _ = proc.communicate(timeout=60)
        client.close()
    assert proc.returncode == 0, out[-3000:]
