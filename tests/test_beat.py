"""The online beat tracker: a steady groove's tempo and beats, and the online object against
its offline twin (polled as a service would)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.live.beat import BeatTracker, beat_accuracy, onset_weights, track_beats
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import SteppedClock
from livedrummer.timeline.events import ONSET_DTYPE
from livedrummer.timeline.performance import Performance
from services.journal import JournalWriter


def rock(bpm: float, bars: int, jitter_s: float = 0.008) -> tuple[np.ndarray, np.ndarray]:
    """Kick on 1 and 3, snare on 2 and 4, hi-hat eighths; the beats played."""
    beat = 60.0 / bpm
    rng = np.random.default_rng(7)
    rows = []
    for k in range(bars * 8):
        t = 1.0 + k * beat / 2
        rows.append((t, 2, 70))  # hi-hat
        if k % 2 == 0:
            rows.append((t, 0 if (k // 2) % 2 == 0 else 1, 100))
    on = np.zeros(len(rows), ONSET_DTYPE)
    on["time_s"] = [t + rng.normal(0, jitter_s) for t, _, _ in rows]
    on["instrument"] = [i for _, i, _ in rows]
    on["velocity"] = [v for _, _, v in rows]
    on.sort(order="time_s")
    return on, 1.0 + beat * np.arange(bars * 4)


@pytest.mark.parametrize("bpm", [72.0, 100.0, 140.0])
def test_a_steady_groove_s_tempo_and_beats_are_found(bpm: float) -> None:
    on, beats = rock(bpm, 12)
    tracker = BeatTracker()
    for row, w in zip(on, onset_weights(on), strict=True):
        tracker.process(float(row["time_s"]), float(w))
    assert tracker.bpm == pytest.approx(bpm, rel=0.02)
    det = track_beats(on["time_s"].astype(np.float64), onset_weights(on), float(beats[-1]) + 0.3)
    assert beat_accuracy(det, beats, float(beats[16])) >= 0.95  # after the first four bars
    # the check can fail: beats half a beat late match none
    assert beat_accuracy(det + 30.0 / bpm, beats, float(beats[16])) == 0.0


def test_polled_online_the_tracker_gives_its_offline_twin_s_beats(groove: Performance) -> None:
    """Polled at 120 Hz (onsets taken as they arrive), every online beat is one the offline
    twin predicts, except where an estimate changed within the tick after an onset."""
    on = groove.onsets[groove.onsets["time_s"] < 20.0]
    w = onset_weights(on)
    times = on["time_s"].astype(np.float64)
    offline = track_beats(times, w, 20.0)
    tracker, online, i = BeatTracker(), [], 0
    for tick in np.arange(0.0, 20.0, 1 / 120):
        while i < times.size and times[i] <= tick:
            tracker.process(float(times[i]), float(w[i]))
            i += 1
        online.append(tracker.beats(tick, tick + 1 / 120))
    got = np.concatenate(online)
    assert got.size > 20 and abs(got.size - offline.size) <= 2
    near = np.min(np.abs(got[:, None] - offline[None, :]), axis=1)
    assert np.mean(near < 0.002) >= 0.95, f"{np.mean(near < 0.002):.2f} of the beats agree"


def test_sessions_export_writes_the_detected_tempo_map(tmp_path: Path) -> None:
    on, _ = rock(100.0, 12, jitter_s=0.004)
    on["note"] = np.where(on["instrument"] == 0, 36, np.where(on["instrument"] == 1, 38, 42))
    on["channel"] = 9
    on["openness"] = np.nan
    on["time_s"] += 5000.0
    w = JournalWriter.create({"performer": 0}, SteppedClock(5000.0), tmp_path, "rock")
    w.append_onsets(on, 0.0, 0)
    w.close()
    out = tmp_path / "rock.mid"
    run = subprocess.run([sys.executable, "-m", "services", "sessions", "export", str(w.path),
                          "-o", str(out)], capture_output=True, text=True, timeout=60)  # fmt: skip
    assert run.returncode == 0, run.stderr
    back = read_midi_file(out, load_note_map("roland-td"))
    played = on["time_s"] - on["time_s"][0]
    heard = back.onsets["time_s"] - back.onsets["time_s"][0]
    assert np.abs(heard - played).max() < 0.002, "the tempo map keeps every onset's time"
    beats = back.grid.beat_s[back.grid.beat_s > 4.0]
    assert 60.0 / np.median(np.diff(beats)) == pytest.approx(100.0, rel=0.02)
    # the file's beats fall on the played beats (kick and snare), not between them
    hits = played[np.isin(on["instrument"], (0, 1))] + float(back.onsets["time_s"][0])
    assert beat_accuracy(beats, hits[hits > 4.5], 4.5, 0.03) >= 0.9
