"""Live practice through a real JACK server: a scripted player on a virtual port; the live
pass scores equal ``practice score`` of the take the rig wrote. Plus the plan's pure parts."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from livedrummer.kit.vocabulary import INSTRUMENT_CODE
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.practice.grade import Level, tally
from livedrummer.practice.live import LiveReadout, meter
from livedrummer.practice.match import Result, match_take, piece_codes
from livedrummer.practice.plan import Ramp, count_in, pass_bounds, pass_clicks, segment
from livedrummer.timeline.events import ONSET_DTYPE

FUNK = "drummer1/eval_session/1_funk-groove1_138_beat_4-4.mid"


def test_loop_segment_clicks_and_count_in(groove_dir: Path) -> None:
    perf = read_midi_file(groove_dir / FUNK, load_note_map("roland-td"))
    seg = segment(perf.grid, perf.duration_s, (2, 3))
    beat = 60 / 138
    assert seg.start_s == pytest.approx(4 * beat, abs=1e-3)
    assert seg.end_s == pytest.approx(12 * beat, abs=1e-3)
    times, accents = pass_clicks(perf.grid, seg, 0.5)
    assert times.size == 8 and accents.tolist() == [True, False, False, False] * 2
    assert times[1] == pytest.approx(2 * beat, abs=1e-3)  # half speed
    quiet, _ = pass_clicks(perf.grid, seg, 1.0, quiet=(1, 1))
    assert quiet.size == 4  # the second bar is silent
    cin, cacc = count_in(perf.grid, seg, 1.0, 2)
    assert cin.size == 8 and cin[0] == pytest.approx(-8 * beat, abs=1e-3) and cacc[0]
    with pytest.raises(ValueError, match="bars"):
        segment(perf.grid, perf.duration_s, (2, 999))


def test_pass_bounds_and_ramp() -> None:
    # first note 0.02 s in, last 3.9 s in: passes meet halfway between 13.9 and 14.02
    bounds = pass_bounds([10.0, 14.0], [4.0, 4.0], 0.02, 3.9, [1.0, 1.0], 0.1)
    assert np.allclose(bounds, [(9.92, 13.96), (13.96, 18.1)])
    half = pass_bounds([10.0], [8.0], 0.02, 3.9, [0.5], 0.1)  # half speed: all times double
    assert np.allclose(half, [(9.94, 18.1)])
    up = Ramp(4.0, target_bpm=108.0)
    assert up.next_bpm(100.0, 90.0) == 104.0
    assert up.next_bpm(106.0, 90.0) == 108.0
    assert up.next_bpm(108.0, 90.0) is None
    assert up.next_bpm(107.99998, 90.0) is None  # a grid's 108 bpm is not exactly 108
    assert Ramp(-5.0, min_accuracy_pct=80.0).next_bpm(100.0, 70.0) is None


def test_readout_streak_and_meter() -> None:
    r = LiveReadout(np.array([1.0, 1.5, 2.0]), np.array([1, 1, 1]), 100.0, Level.EASY)
    a = r.process(1.010, 1)
    b = r.process(1.560, 1)
    c = r.process(2.300, 1)
    assert (a.on_time, a.streak, b.on_time, b.streak) == (True, 1, False, 0)
    assert c.offset_ms is None
    assert meter(20.0) == "-----|-*---" and meter(-80.0) == "*----|-----"


def test_readout_agrees_with_the_offline_judge_when_hits_are_unambiguous() -> None:
    """Fed one hit at a time, the provisional readout pairs hits as match_take does wherever
    no two hits fight over one note (notes of one piece farther apart than two windows)."""
    rng = np.random.default_rng(9)
    ref = np.zeros(120, dtype=ONSET_DTYPE)
    ref["time_s"] = np.arange(120) * 0.125
    ref["instrument"] = [INSTRUMENT_CODE[("kick", "snare", "hihat")[i % 3]] for i in range(120)]
    played = ref.copy()
    played["time_s"] += rng.normal(0.0, 0.025, ref.size)
    played = np.delete(played, [5, 40, 77])
    played = played[np.argsort(played["time_s"])]
    readout = LiveReadout(ref["time_s"], piece_codes(ref), 100.0, Level.EASY)
    live = [
        readout.process(float(h["time_s"]), int(c))
        for h, c in zip(played, piece_codes(played), strict=True)
    ]
    offline = match_take(ref, played)
    hit = offline.notes["result"] == Result.HIT
    want = sorted(np.round(offline.notes["offset_ms"][hit], 6).tolist())
    got = sorted(round(x.offset_ms, 6) for x in live if x.offset_ms is not None)
    assert got == want and len(got) == 117
    whole = tally(offline.notes, offline.extra.size).accuracy_pct
    assert live[-1].accuracy_pct == pytest.approx(whole, abs=1e-9)


def test_judged_times_are_the_take_files(tmp_path: Path) -> None:
    """The pass judges its hits on the take's tick grid, so ``practice score`` of the take file
    sees the very times judged: a hit a hair either side of a grade's edge keeps its grade."""
    from services.practice.take import on_take_grid, take_lead_s, write_take

    rng = np.random.default_rng(4)
    hits = np.zeros(40, dtype=ONSET_DTYPE)
    hits["time_s"] = np.sort(rng.uniform(-0.5, 8.0, hits.size))
    hits["note"], hits["velocity"], hits["channel"] = 38, 90, 9
    hits["instrument"] = INSTRUMENT_CODE["snare"]
    grid = on_take_grid(hits["time_s"])
    step = 60.0 / (120.0 * 1920)
    assert np.all(np.abs(grid - hits["time_s"]) <= step / 2 + 1e-12)
    assert np.any(np.abs(grid - hits["time_s"]) > step / 10)  # the grid moved them
    write_take(tmp_path / "take.mid", hits)
    back = read_midi_file(tmp_path / "take.mid", load_note_map("roland-td")).onsets["time_s"]
    back = back - take_lead_s(tmp_path / "take.mid")
    assert np.abs(back - grid).max() < 1e-9  # what the pass judged, to the nanosecond
    assert np.all(on_take_grid(grid) == grid)  # and the grid is its own: judged once, kept


rtmidi = pytest.importorskip("rtmidi")


def wait_port(name: str, timeout_s: float = 20.0) -> str:
    probe = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "probe")
    try:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            hits = [q for q in probe.get_ports() if q.endswith(f":{name}")]
            if hits:
                return str(hits[0])
            time.sleep(0.05)
        raise AssertionError(f"no JACK input port {name!r}: {probe.get_ports()}")
    finally:
        probe.delete()


def test_live_pass_equals_score_of_its_take(
    jack_rig_server: str, groove_dir: Path, tmp_path: Path
) -> None:
    """The JACK server runs realtime (``-R``, as docs/guide/rig.md asks of a rig): without it, CPU
    hogs beside the test stall JACK's cycle by up to 0.7 s (jackd logs the xruns), the player's
    notes reach the rig in late batches, their driver stamps late with them, and the planted
    result is gone; a rig has the same need of its JACK server."""
    ref = groove_dir / FUNK
    take = tmp_path / "take.mid"
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "services",
            "practice",
            str(ref),
            "--virtual",
            "pads",
            "--api",
            "jack",
            "--map",
            "roland-td",
            "--bars",
            "2:3",
            "--count-in",
            "1",
            "--no-sound",
            "--no-window",
            "--json",
            "--take",
            str(take),
            "--seconds",
            "40",
            "--passes",
            "1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        assert proc.stdout is not None
        plan = json.loads(proc.stdout.readline())
        assert plan["pass"] == 1 and plan["bars"] == [2, 3]
        out = rtmidi.MidiOut(rtmidi.API_UNIX_JACK, "player")
        out.open_port(out.get_ports().index(wait_port("pads")))
        notes = plan["notes"]
        rng = np.random.default_rng(2)
        offsets = np.clip(rng.normal(8.0, 10.0, len(notes)), -30, 30) / 1e3
        skip = {3, 11}  # missed
        moved = 7  # played on tom1 (no tom1 in this groove)
        sent = 0
        for i, (t, note, velocity) in enumerate(notes):
            if i in skip:
                continue
            while time.monotonic() < t + offsets[i]:
                time.sleep(0.0002)
            out.send_message([0x99, 48 if i == moved else note, velocity])
            sent += 1
        out.close_port()
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, stderr
    lines = [json.loads(line) for line in stdout.splitlines()]
    hits = [ln["hit"] for ln in lines if "hit" in ln]
    strays = [ln["stray"] for ln in lines if "stray" in ln]  # a hit no pass owned: its line
    assert len(hits) == sent, (lines[-1], strays, [h["time_s"] for h in hits][:6])
    assert not strays and lines[-1]["stray_hits"] == lines[-1]["doubled_hits"] == 0
    live = next(ln for ln in lines if "pass_result" in ln)
    assert (live["missed"], live["wrong_piece"], live["extra"]) == (2, 1, 0)
    assert live["hits"] == len(notes) - 3
    assert lines[-1]["done"] and lines[-1]["passes"] == 1
    scored = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "practice",
            "score",
            str(ref),
            str(take),
            "--map",
            "roland-td",
            "--take-map",
            "roland-td",
            "--bars",
            "2:3",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert scored.returncode == 0, scored.stderr
    score = json.loads(scored.stdout)
    for key in ("reference_notes", "hits", "missed", "wrong_piece", "extra", "perfect", "good"):
        assert score[key] == live[key], key
    assert score["mean_offset_ms"] == pytest.approx(live["mean_offset_ms"], abs=0.2)
    pairs = zip(score["notes"], live["notes"], strict=True)
    assert all(a["result"] == b["result"] for a, b in pairs)
    # the planted offsets plus the MIDI path (a JACK period or two, the player's own lateness)
    assert live["mean_offset_ms"] == pytest.approx(1e3 * offsets.mean() + 5.0, abs=10.0)


def test_ramp_and_quiet_count_drill(jack_server: str, groove_dir: Path, tmp_path: Path) -> None:
    """Auto up: 240 then 260 bpm, stopping at the target; the click is silent every other bar;
    a pass nobody played is all missed and kept in the database."""
    env = {**os.environ, "LIVEDRUMMER_HOME": str(tmp_path / "home")}
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "practice",
            str(groove_dir / FUNK),
            "--virtual",
            "p",
            "--api",
            "jack",
            "--map",
            "roland-td",
            "--bars",
            "2:3",
            "--bpm",
            "240",
            "--ramp",
            "20",
            "--ramp-target",
            "260",
            "--quiet-count",
            "1:1",
            "--no-sound",
            "--json",
            "--no-window",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(line) for line in proc.stdout.splitlines()]
    plans = [ln for ln in lines if "notes" in ln and "pass" in ln]
    assert [p["bpm"] for p in plans] == [240.0, 260.0]
    for p in plans:
        beat = 60.0 / p["bpm"]
        clicks = np.array(p["clicks_s"]) - p["start_s"]
        # one count-in bar, then only the first of the two bars (the second is quiet)
        assert clicks == pytest.approx(np.array([-4, -3, -2, -1, 0, 1, 2, 3]) * beat, abs=1e-6)
    results = [ln for ln in lines if "pass_result" in ln]
    assert [r["missed"] for r in results] == [r["reference_notes"] for r in results]
    assert lines[-1]["passes"] == 2
    hist = subprocess.run(
        [sys.executable, "-m", "services", "practice", "history", "--json"],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert [s["kind"] for s in json.loads(hist.stdout)["sessions"]] == ["live", "live"]
