"""The online beat tracker: a steady groove's tempo and beats, and the online object against
its offline twin (polled as a service would)."""

from __future__ import annotations

import itertools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.live.beat import (
    BeatTracker,
    beat_accuracy,
    beat_precision,
    downbeat_weights,
    onset_weights,
    track_beats,
)
from livedrummer.live.cues import BarCues, parse_cues
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.timeline.clock import SteppedClock
from livedrummer.timeline.events import ONSET_DTYPE
from livedrummer.timeline.performance import Performance
from services.input.journal import JournalWriter


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
    run = subprocess.run(
        [sys.executable, "-m", "services", "sessions", "export", str(w.path), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=60,
    )
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


def funk(bpm: float, bars: int, crash: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """A syncopated groove: hi-hat sixteenths, snare on 2 and 4, kicks on 1, the "and" of 2
    and the "a" of 3 (off the beat), a crash on each bar's 1; the beats played."""
    beat = 60.0 / bpm
    rng = np.random.default_rng(11)
    rows = []
    for b in range(bars):
        t0 = 1.0 + 4 * b * beat
        rows += [(t0 + s * beat / 4, 2, 90 if s % 4 == 0 else 55) for s in range(16)]
        rows += [(t0 + x * beat, 0, 105) for x in (0.0, 1.5, 2.75)]
        rows += [(t0 + x * beat, 1, 115) for x in (1.0, 3.0)]
        if crash:
            rows.append((t0, 9, 100))
    on = np.zeros(len(rows), ONSET_DTYPE)
    on["time_s"] = [t + rng.normal(0, 0.006) for t, _, _ in rows]
    on["instrument"] = [i for _, i, _ in rows]
    on["velocity"] = [v for _, _, v in rows]
    on.sort(order="time_s")
    return on, 1.0 + beat * np.arange(bars * 4)


def polled(on: np.ndarray, end_s: float) -> tuple[BeatTracker, list[np.ndarray]]:
    """A tracker fed as a service feeds it, asked for the beats of each 120 Hz tick."""
    times, w, d = on["time_s"].astype(np.float64), onset_weights(on), downbeat_weights(on)
    tracker, out, i = BeatTracker(), [], 0
    for tick in np.arange(0.0, end_s, 1 / 120):
        while i < times.size and times[i] <= tick:
            tracker.process(float(times[i]), float(w[i]), float(d[i]))
            i += 1
        out.append(tracker.beats(tick, tick + 1 / 120))
    return tracker, out


@pytest.mark.parametrize("bpm", [84.0, 118.0])
def test_a_syncopated_groove_locks_on_the_beat_and_the_beats_never_jump(bpm: float) -> None:
    on, beats = funk(bpm, 12)
    det = track_beats(
        on["time_s"].astype(np.float64),
        onset_weights(on),
        float(beats[-1]) + 0.3,
        downbeats=downbeat_weights(on),
    )
    assert beat_accuracy(det, beats, float(beats[16])) >= 0.95
    _, online = polled(on, float(beats[-1]) + 0.3)
    got = np.concatenate(online)
    gaps = np.diff(got[got > beats[8]])  # once locked (after two bars)
    period = 60.0 / bpm
    assert gaps.size > 20
    assert np.abs(gaps / period - 1.0).max() < 0.1, "a beat jumped"


def test_bars_start_on_the_kick_and_crash_and_count_up() -> None:
    on, beats = funk(100.0, 12)
    tracker = BeatTracker()
    starts: list[tuple[float, int]] = []
    times, w, d = on["time_s"].astype(np.float64), onset_weights(on), downbeat_weights(on)
    for i in range(times.size):
        tracker.process(float(times[i]), float(w[i]), float(d[i]))
        nxt = float(times[i + 1]) if i + 1 < times.size else float(beats[-1]) + 0.3
        starts += tracker.bars(float(times[i]), nxt)
    late = [(t, n) for t, n in starts if t > beats[24]]  # after six bars
    assert len(late) >= 5
    bar_starts = beats[::4]
    assert all(np.min(np.abs(bar_starts - t)) < 0.05 for t, _ in late), "a bar's 1 is its kick"
    numbers = [n for _, n in starts]
    assert numbers[0] == 1 and all(b >= a for a, b in itertools.pairwise(numbers))
    assert numbers[-1] - numbers[0] >= len(starts) - 2  # one per bar (one correction at most)
    # the check can fail: a bar start on the 3 (the kick's other place) is no bar's 1
    assert not any(np.min(np.abs(bar_starts + 2 * 0.6 - t)) < 0.05 for t, _ in late)


def test_a_corrected_downbeat_never_skips_a_bar_number() -> None:
    """The demo groove (tracked at double tempo) as a live synth hears it: onsets stamped up to
    2 ms late, bars asked for at 120 Hz from a random tick phase. With this seed the tracker
    corrects its downbeat just after a bar start had passed, so the next start comes six beats
    on; the beat count numbered it two bars on, and a cue at bar 6 fired a bar early."""
    from services.cli.files import demo_groove

    on = read_midi_file(demo_groove(), load_note_map("general-midi")).onsets
    on = on[on["time_s"] < 20.0]
    rng = np.random.default_rng(15)
    on["time_s"] += rng.uniform(0, 0.002, on.size)
    on = np.sort(on, order="time_s")
    w, d = onset_weights(on), downbeat_weights(on)
    tracker, i, start, starts = BeatTracker(), 0, -1e9, []
    for now in np.arange(0.0, 20.0, 1 / 120) + rng.uniform(0, 1 / 120):
        while i < on.size and on["time_s"][i] <= now:
            tracker.process(float(on["time_s"][i]), float(w[i]), float(d[i]))
            i += 1
        starts += tracker.bars(max(start, now - 1.0), now + 0.2)
        start = now + 0.2
    numbers = [n for _, n in starts]
    assert all(b - a in (0, 1) for a, b in itertools.pairwise(numbers)), starts
    assert tracker.period_s is not None
    # the twin without jitter: bars 4 and 6 eight of its beats apart
    (t4,), (t6,) = ([t for t, n in starts if n == k][-1:] for k in (4, 6))
    assert abs((t6 - t4) / tracker.period_s - 8.0) < 1.0, starts


def test_bar_cues_fire_once_each_in_bar_order() -> None:
    cues = parse_cues(
        {
            "cue": [
                {"name": "b", "bar": 5, "preset": "relaxed"},
                {"name": "a", "bar": 2},
                {"name": "x", "at_s": 3.0},
                {"name": "n"},
            ]
        },
        "test",
    )
    fire = BarCues(cues)
    assert fire.due([]) == [] and fire.due([(0.0, 1)]) == []
    assert [(t, c.name) for t, c in fire.due([(2.0, 2)])] == [(2.0, "a")]
    assert fire.due([(2.0, 2), (4.0, 3)]) == []  # a repeated bar fires nothing again
    # a skipped bar 5 still fires, at the start of the first bar past it
    assert [(t, c.name) for t, c in fire.due([(8.0, 4), (9.0, 6)])] == [(9.0, "b")]
    assert fire.due([(11.0, 7)]) == []


def test_a_flood_keeps_each_update_bounded() -> None:
    """1,000 onsets a second: the tracker keeps its newest max_onsets (the tempo's pair
    histogram is quadratic in them), so the flood costs what ordinary playing costs."""
    from livedrummer.live.beat import BeatParams, BeatTracker

    tracker = BeatTracker()
    for k in range(3000):
        tracker.process(100.0 + k / 1000.0, 1.0)
    assert len(tracker._onsets) <= BeatParams().max_onsets


def test_precision_counts_the_extra_beats_that_accuracy_forgives() -> None:
    reference = np.arange(0.0, 20.0, 0.5)
    double = np.arange(0.0, 20.0, 0.25)  # double tempo: every reference beat, and one between
    off = reference + 0.25  # on the "and": none
    assert beat_accuracy(double, reference, 2.0) == 1.0
    assert beat_precision(double, reference, 2.0) == pytest.approx(0.5, abs=0.02)
    assert beat_precision(reference + 0.02, reference, 2.0) == 1.0
    assert beat_precision(off, reference, 2.0) == 0.0
    assert beat_precision(np.zeros(0), reference, 2.0) == 0.0
    late = np.concatenate([reference, [25.0, 30.0]])  # past the reference's end: not counted
    assert beat_precision(late, reference, 2.0) == 1.0


def pushed(bpm: float, bars: int) -> tuple[np.ndarray, np.ndarray]:
    """Hi-hat eighths, snare on 2 and 4, the kick on 1 and pushed onto the "and"s of 2 and 3
    (two of its three strokes off the beat); the beats played."""
    beat = 60.0 / bpm
    rng = np.random.default_rng(3)
    rows = []
    for b in range(bars):
        t0 = 1.0 + 4 * b * beat
        rows += [(t0 + s * beat / 2, 2, 70) for s in range(8)]
        rows += [(t0 + x * beat, 0, 110) for x in (0.0, 1.5, 2.5)]
        rows += [(t0 + x * beat, 1, 110) for x in (1.0, 3.0)]
    on = np.zeros(len(rows), ONSET_DTYPE)
    on["time_s"] = [t + rng.normal(0, 0.006) for t, _, _ in rows]
    on["instrument"] = [i for _, i, _ in rows]
    on["velocity"] = [v for _, _, v in rows]
    on.sort(order="time_s")
    return on, 1.0 + beat * np.arange(bars * 4)


@pytest.mark.parametrize("bpm", [96.0, 127.0])
def test_a_snare_backbeat_holds_the_beat_against_a_kick_on_the_ands(bpm: float) -> None:
    from livedrummer.live.beat import BeatParams

    on, beats = pushed(bpm, 12)
    args = (on["time_s"].astype(np.float64), onset_weights(on), float(beats[-1]) + 0.3)
    down = downbeat_weights(on)
    det = track_beats(*args, downbeats=down)
    assert beat_accuracy(det, beats, float(beats[16])) >= 0.95
    assert beat_precision(det, beats, float(beats[16])) >= 0.95
    # without the backbeat rule the kicks hold the grid on the "and"
    kicks_only = track_beats(*args, BeatParams(backbeat=math.inf), downbeats=down)
    assert beat_accuracy(kicks_only, beats, float(beats[16])) <= 0.1
