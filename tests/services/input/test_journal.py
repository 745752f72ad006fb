"""Session journal: record round trips, torn tails, corruption, kill -9, MIDI export."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from livedrummer.errors import JournalError
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.protocol import Gap, GapReason
from livedrummer.protocol import journal as jr
from livedrummer.timeline.clock import SteppedClock
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE
from services.cli.files import demo_groove
from services.input.journal import (
    JournalWriter,
    export_session,
    find_session,
    list_sessions,
    load_journal,
)


def onsets(n: int, t0: float = 0.0) -> np.ndarray:
    rows = np.zeros(n, ONSET_DTYPE)
    rows["time_s"] = t0 + np.arange(n) * 0.1
    rows["note"] = 36 + np.arange(n) % 10
    rows["velocity"] = 1 + np.arange(n) % 127
    rows["channel"] = 9
    rows["openness"] = np.nan
    return rows


def controls(n: int, t0: float = 0.0) -> np.ndarray:
    rows = np.zeros(n, CONTROL_DTYPE)
    rows["time_s"] = t0 + np.arange(n) * 0.1
    rows["number"] = 4
    rows["value"] = np.arange(n) % 128
    return rows


def write_session(tmp_path: Path, batches: int = 5) -> JournalWriter:
    clock = SteppedClock(100.0)
    w = JournalWriter.create({"performer": 2, "source": "test"}, clock, tmp_path, "s1")
    for b in range(batches):
        clock.advance(0.5)
        w.append_onsets(onsets(3, b), clock.now(), 2 * b)
        w.append_controls(controls(2, b), clock.now(), 2 * b + 1)
    w.append_gap(Gap(4, 1.0, 2.0, GapReason.QUEUE_FULL), clock.now(), 99)
    w.close({"published": 10})
    return w


def test_writer_and_reader_round_trip(tmp_path: Path) -> None:
    w = write_session(tmp_path)
    j = load_journal(w.path)
    assert w.path == tmp_path / "s1.ldj"
    assert j.meta is not None and j.meta["performer"] == 2 and j.meta["session"] == "s1"
    assert j.meta["start_s"] == 100.0
    assert j.onsets.tobytes() == np.concatenate([onsets(3, b) for b in range(5)]).tobytes()
    assert j.controls.tobytes() == np.concatenate([controls(2, b) for b in range(5)]).tobytes()
    assert j.onset_arrivals_s.tolist() == [
        100.0 + 0.5 * (b + 1) for b in range(5) for _ in range(3)
    ]
    assert j.gaps == [Gap(4, 1.0, 2.0, GapReason.QUEUE_FULL)]
    assert j.end == {"published": 10}
    assert j.clean and j.records == 1 + 10 + 1 + 1 and not j.stop_reason


def test_every_torn_tail_is_read_up_to_the_last_whole_record(tmp_path: Path) -> None:
    data = write_session(tmp_path).path.read_bytes()
    boundaries = [jr.FILE_HEADER.size]
    pos = jr.FILE_HEADER.size
    while pos < len(data):
        pos += 8 + int.from_bytes(data[pos : pos + 4], "little")
        boundaries.append(pos)
    assert boundaries[-1] == len(data)
    for cut in range(jr.FILE_HEADER.size, len(data) + 1):
        j = jr.read_journal(data[:cut], "cut")
        whole = max(b for b in boundaries if b <= cut)
        assert j.records == boundaries.index(whole)
        assert j.discarded_bytes == cut - whole
        assert bool(j.stop_reason) == (cut != whole)
        assert j.onsets.size == 3 * min(5, j.records // 2)  # meta, then (onsets, controls) pairs


def test_corruption_in_the_middle_stops_there_and_says_so(tmp_path: Path) -> None:
    data = bytearray(write_session(tmp_path).path.read_bytes())
    first = jr.FILE_HEADER.size
    second = first + 8 + int.from_bytes(data[first : first + 4], "little")  # first onsets record
    data[second + 8 + 30] ^= 0xFF
    j = jr.read_journal(bytes(data), "bad")
    assert j.records == 1 and j.meta is not None and j.onsets.size == 0
    assert "corrupt record" in j.stop_reason and str(second) in j.stop_reason
    assert j.discarded_bytes == len(data) - second
    assert not j.clean


def test_bad_headers_are_named_errors(tmp_path: Path) -> None:
    with pytest.raises(JournalError, match="shorter"):
        jr.read_journal(b"LDJ", "x")
    with pytest.raises(JournalError, match="not a livedrummer journal"):
        jr.read_journal(b"MThd" + bytes(20), "x")
    with pytest.raises(JournalError, match="version"):
        jr.read_journal(jr.FILE_HEADER.pack(jr.MAGIC, 9), "x")
    bad = onsets(1)
    bad["instrument"] = 200
    data = jr.file_header() + jr.onsets_record(bad, 0.0, 0)
    with pytest.raises(JournalError, match="instrument"):
        jr.read_journal(data, "x")


WRITER = textwrap.dedent(
    """
    import sys
    import numpy as np
    from pathlib import Path
    from livedrummer.timeline.clock import MonotonicClock
    from livedrummer.timeline.events import ONSET_DTYPE
    from services.input.journal import JournalWriter
    w = JournalWriter.create({"performer": 0}, MonotonicClock(), Path(sys.argv[1]), "crash", 0.05)
    seq = 0
    while True:
        rows = np.zeros(7, ONSET_DTYPE)
        rows["time_s"] = seq
        rows["note"] = 38
        rows["velocity"] = 100
        w.append_onsets(rows, float(seq), seq)
        seq += 1
    """
)


def test_kill_9_mid_session_loses_nothing_written(tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(tmp_path)], cwd=Path(__file__).parents[3]
    )
    path = tmp_path / "crash.ldj"
    try:
        deadline = time.monotonic() + 30
        while (not path.exists() or path.stat().st_size < 200_000) and time.monotonic() < deadline:
            assert proc.poll() is None, "writer died"
            time.sleep(0.01)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    j = load_journal(path)
    assert j.end is None and not j.clean
    batches = j.onsets.size // 7
    assert j.onsets.size == 7 * batches and batches > 1000
    assert j.onsets["time_s"].tolist() == np.repeat(np.arange(batches), 7).tolist()


def test_export_to_midi_reads_back_as_the_same_performance(tmp_path: Path) -> None:
    note_map = load_note_map("roland-td")
    perf = read_midi_file(demo_groove(), note_map)
    clock = SteppedClock(5000.0)
    w = JournalWriter.create({"performer": 0}, clock, tmp_path, "groove")
    offset = 5000.25
    on = perf.onsets.copy()
    on["time_s"] += offset
    ctl = perf.controls.copy()
    ctl["time_s"] += offset
    # Interleave batches as a live daemon would journal them (controls and onsets separately).
    for k in range(0, on.size, 50):
        w.append_onsets(on[k : k + 50], 0.0, k)
    for k in range(0, ctl.size, 64):
        w.append_controls(ctl[k : k + 64], 0.0, k)
    w.close()
    out = tmp_path / "groove.mid"
    export_session(w.path, out)
    back = read_midi_file(out, note_map)
    assert back.onsets.size == perf.onsets.size
    assert back.controls.size == perf.controls.size
    origin = min(perf.onsets["time_s"].min(), perf.controls["time_s"].min())
    half_tick = 0.5 * 60 / (120 * 1920)
    assert (
        np.abs(back.onsets["time_s"] - (perf.onsets["time_s"] - origin)).max() <= half_tick + 1e-9
    )
    for name in ("note", "velocity", "channel", "instrument", "zone", "hihat"):
        assert back.onsets[name].tolist() == perf.onsets[name].tolist(), name
    np.testing.assert_array_equal(back.onsets["openness"], perf.onsets["openness"])
    for name in ("kind", "channel", "number", "value"):
        assert back.controls[name].tolist() == perf.controls[name].tolist(), name


def test_session_listing_and_lookup(tmp_path: Path) -> None:
    write_session(tmp_path)
    clock = SteppedClock()
    w2 = JournalWriter.create({"performer": 1}, clock, tmp_path, "s2-crashed")
    w2.append_onsets(onsets(4), 0.0, 0)  # never closed
    infos = list_sessions(tmp_path)
    assert [i.session for i in infos] == ["s1", "s2-crashed"]
    assert (infos[0].onsets, infos[0].controls, infos[0].clean) == (15, 10, True)
    assert infos[0].duration_s == pytest.approx(4.2)
    assert (infos[1].onsets, infos[1].clean) == (4, False)
    assert find_session("s1", tmp_path) == tmp_path / "s1.ldj"
    assert find_session("s2", tmp_path) == tmp_path / "s2-crashed.ldj"
    with pytest.raises(JournalError, match="ambiguous"):
        find_session("s", tmp_path)
    with pytest.raises(JournalError, match="no such session"):
        find_session("zzz", tmp_path)
    with pytest.raises(JournalError, match="cannot create"):
        JournalWriter.create({}, clock, tmp_path, "s1")


def test_fsync_runs_in_the_background_or_in_line_as_configured(tmp_path: Path) -> None:
    clock = SteppedClock()
    inline = JournalWriter.create({}, clock, tmp_path, "inline", fsync_interval_s=0)
    for k in range(3):
        inline.append_onsets(onsets(1), 0.0, k)
    assert inline.syncs == 3
    inline.close()
    assert inline.syncs == 4
    background = JournalWriter.create({}, clock, tmp_path, "bg", fsync_interval_s=0.01)
    background.append_onsets(onsets(1), 0.0, 0)
    deadline = time.monotonic() + 10
    while background.syncs == 0 and time.monotonic() < deadline:
        time.sleep(0.005)
    assert background.syncs == 1
    idle = background.syncs
    time.sleep(0.05)  # several intervals
    assert background.syncs == idle  # nothing appended since: nothing synced
    background.close()
    assert background.syncs == idle + 1 and load_journal(background.path).clean
