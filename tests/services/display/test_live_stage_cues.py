"""Bar cues with a camera and a blackout, live: the synth counts bars with its beat tracker and
sends each bar cue's stage part to the displays (protocol kind STAGE_CUE) stamped with the
bar's show time; the display applies it in the first frame that shows that time.

The end-to-end test runs ``up --demo --headless --cues FILE`` (no OSC) with a cut at bar 4 and a
blackout at bar 6 (bars the tracker has settled on), and reads the frames the display recorded: frames.jsonl names the frame in
which each cue was applied and its show time, every frame before it keeps the old camera (or
is lit), every one after has the new one (or goes black), and the PNGs change with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from livedrummer import protocol as p
from livedrummer.errors import ProtocolError
from livedrummer.live.beat import BeatTracker, downbeat_weights, onset_weights
from livedrummer.live.cues import Cue, parse_cues, stage_cue_of, stage_cue_rows
from tests.services.cli.test_live_up import launch
from tests.services.show.test_live_osc import Frames


def test_a_stage_cue_round_trips_on_the_pose_stream_and_is_checked() -> None:
    cues = parse_cues(
        {
            "cue": [
                {"name": "cut", "bar": 3, "camera": 4, "cut": True},
                {"name": "dark", "bar": 5, "blackout": True},
                {"name": "style", "bar": 6, "preset": "relaxed"},
            ]
        },
        "test",
    )
    rows = stage_cue_rows(
        [(10.5, 3, cues["cut"]), (13.5, 5, cues["dark"]), (15.0, 6, cues["style"])]
    )
    assert rows.size == 2, "a cue with no camera or blackout sends nothing to the displays"
    frames = p.encode(p.Message(p.Kind.STAGE_CUE, rows, performer=1, seq=4, stream=p.Stream.POSES))
    back = p.decode(frames)
    assert back.kind is p.Kind.STAGE_CUE and back.rows.tobytes() == rows.tobytes()
    assert stage_cue_of(back.rows[0]) == Cue("bar 3", bar=3, camera="overhead", cut=True)
    assert stage_cue_of(back.rows[1]) == Cue("bar 5", bar=5, blackout=True)
    bad = rows.copy()
    bad["camera"][1] = 9
    with pytest.raises(ProtocolError, match=r"row 1\.camera"):
        p.encode(p.Message(p.Kind.STAGE_CUE, bad))
    bad = rows.copy()
    bad["blackout"][0] = 2
    with pytest.raises(ProtocolError, match=r"row 0\.blackout"):
        p.decode([frames[0], bad.tobytes()])


def test_the_display_applies_a_stage_cue_at_its_show_time_and_a_replay_agrees() -> None:
    from livedrummer.kit.loader import load_kit
    from services.display.showctl import DisplayShow, replay_stage

    kit = load_kit("rock5")
    show = DisplayShow(kit, "stage", None)
    cues = parse_cues(
        {
            "cue": [
                {"name": "cut", "bar": 3, "camera": "front", "cut": True},
                {"name": "dark", "bar": 5, "blackout": True},
            ]
        },
        "t",
    )
    show.schedule(stage_cue_rows([(2.05, 5, cues["dark"]), (1.02, 3, cues["cut"])]))
    seen = []
    for k in range(40):  # 10 fps, each frame shown 0.1 s after it is rendered
        render = k * 0.1
        fired = show.apply(render, render + 0.1)
        seen.append((render, show.stage.camera, show.stage.darkness(render), fired))
    cut = next(k for k, s in enumerate(seen) if s[1] == "front")
    assert seen[cut][3] == [("bar 3", 1.02, False)] and cut == 10  # the frame shown at 1.1 s
    assert all(s[1] == "stage" for s in seen[:cut]) and all(s[1] == "front" for s in seen[cut:])
    dark = next(k for k, s in enumerate(seen) if s[2] > 0)
    assert seen[dark][3] == [("bar 5", 2.05, False)] and dark == 20  # shown at 2.1 s
    # the fade starts on the cue's show time (render 1.95 s), not at the frame: 0.05 s into
    # the 0.5 s smoothstep
    assert seen[dark][2] == pytest.approx(0.1 * 0.1 * (3 - 2 * 0.1))
    assert seen[-1][2] == 1.0 and show.late_cues == 0
    # a cue that arrives after the frame that should have shown it: in the next frame, late
    show.schedule(stage_cue_rows([(3.5, 9, cues["cut"])]))
    assert show.late_cues == 1
    assert show.apply(4.0, 4.1) == [("bar 9", 3.5, True)]
    replay = replay_stage(kit, show)
    for render, camera, darkness, _ in seen:
        view, dark_now = replay.at(render)
        assert replay.stage.camera == camera and dark_now == pytest.approx(darkness)
        assert view == show.stage.cameras[camera]


def offline_bar_cues(bars: tuple[int, ...]) -> tuple[list[float], float]:
    """The offline twin of the synth's bar counting on the demo groove: its onsets fed to a
    tracker as they come, the tracker asked for bars at 120 Hz as the synth ticks (a lead
    ahead, as the synth asks); the start times that fire cues at ``bars``
    (:class:`~livedrummer.live.cues.BarCues`), and the tracker's beat period at the end."""
    from livedrummer.live.cues import BarCues
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from services.cli.files import demo_groove
    from services.synth.service import BAR_LEAD_S

    on = read_midi_file(demo_groove(), load_note_map("general-midi")).onsets
    on = on[on["time_s"] < 20.0]
    weights, down = onset_weights(on), downbeat_weights(on)
    cues = BarCues({f"b{n}": Cue(f"b{n}", bar=n) for n in bars})
    tracker, i, start, fired = BeatTracker(), 0, -1e9, {}
    for now in np.arange(0.0, 20.0, 1 / 120):
        while i < on.size and on["time_s"][i] <= now:
            tracker.process(float(on["time_s"][i]), float(weights[i]), float(down[i]))
            i += 1
        ahead = now + BAR_LEAD_S
        for at, cue in cues.due(tracker.bars(max(start, now - 1.0), ahead)):
            fired[cue.bar] = at
        start = ahead
    assert tracker.period_s is not None and set(fired) == set(bars)
    return [fired[n] for n in bars], tracker.period_s


def test_up_cuts_the_camera_and_blacks_out_on_the_bars_the_tracker_counts(
    gl_ok: None, tmp_path: Path
) -> None:
    cues = tmp_path / "cues.toml"
    cues.write_text(
        '[[cue]]\nname = "cut"\nbar = 4\ncamera = "front"\ncut = true\n\n'
        '[[cue]]\nname = "dark"\nbar = 6\nblackout = true\n'
    )
    proc = launch(
        tmp_path, "--headless", "--seconds", "17", "--png", "--fps", "10", "--cues", str(cues)
    )
    out, _ = proc.communicate(timeout=180)
    assert proc.returncode == 0, out[-3000:]
    frames = Frames(tmp_path / "frames")
    rows = frames.read()
    applied = {name: (k, at, late) for k, r in enumerate(rows)
               for name, at, late in r.get("cues", [])}  # type: ignore[attr-defined]  # fmt: skip
    assert set(applied) == {"bar 4", "bar 6"}, f"cues applied: {applied}\n{out[-2000:]}"
    (cut, cut_s, cut_late), (dark, dark_s, dark_late) = applied["bar 4"], applied["bar 6"]
    show = [float(r["show_s"]) for r in rows]  # type: ignore[arg-type]
    # each lands in the first frame whose show time reaches the bar's show time (or, where
    # an overloaded machine made the synth send it late, counted, in the next frame drawn)
    assert cut_s <= show[cut] and dark_s <= show[dark]
    assert cut_late or show[cut - 1] < cut_s
    assert dark_late or show[dark - 1] < dark_s
    assert ("stage cue" in out) == (cut_late or dark_late), out[-2000:]
    assert all(r["camera"] == "stage" for r in rows[:cut])
    assert all(r["camera"] == "front" for r in rows[cut:])
    assert all(r["dark"] == 0.0 for r in rows[:dark]) and float(rows[dark]["dark"]) > 0  # type: ignore[arg-type]
    before, after = frames.png(rows[cut - 1]), frames.png(rows[cut])
    assert np.abs(after.astype(int) - before.astype(int)).mean() > 5.0, "the cut shows"
    black = [r for r in rows if float(r["show_s"]) > dark_s + 0.6]  # type: ignore[arg-type]
    assert black and all(r["dark"] == 1.0 for r in black)
    assert all(frames.png(r).max() <= 1 for r in black[:3]), "blacked-out frames are black"
    assert frames.png(rows[dark - 1]).mean() > 5, "lit before the blackout's bar"
    # the bars are the tracker's (it follows this 80 bpm groove at 160: two of the file's bars
    # are 16 of its beats): as many of its beats apart as its offline twin counts between
    # those bars (8), give or take the beats a corrected downbeat moves a bar start by (the
    # live onsets' timing under load moves the tracker's corrections)
    (twin_cut, twin_dark), period = offline_bar_cues((4, 6))
    beats = (dark_s - cut_s) / period
    assert abs(beats - (twin_dark - twin_cut) / period) <= 2.5, (beats, twin_cut, twin_dark)
    assert cut_s - show[next(k for k, r in enumerate(rows) if r["pose_s"] is not None)] > 2.0


def test_bench_latency_measures_with_and_without_show_control(gl_ok: None) -> None:
    """``bench latency --both``: each rate with nothing and with OSC ports and both strips on,
    and a table of the medians side by side (figures, not asserted: docs/reference/osc.md quotes them)."""
    import subprocess
    import sys

    from tests.services.cli.test_live_up import REPO

    bad = subprocess.run(
        [sys.executable, "-m", "services", "bench", "latency", "--overlay", "scroe"],
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert bad.returncode == 2 and "unknown overlay 'scroe'" in bad.stderr
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "bench",
            "latency",
            "--rates",
            "10",
            "--seconds",
            "0.5",
            "--both",
        ],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=240,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    out = run.stdout
    assert "10 plain" in out and "10 show" in out
    table = out[out.index("show control off / on") :].splitlines()
    assert "load average" in table[0]
    row = next(line for line in table if line.strip().startswith("10 D=30"))
    cells = [c.split("/") for c in row.split("|")[1:]]
    assert len(cells) == 5 and all(len(c) == 2 for c in cells)
    medians = [float(x.split("(")[0]) for c in cells for x in c]
    assert all(np.isfinite(m) and m > 0 for m in medians), row  # every stage measured both ways
