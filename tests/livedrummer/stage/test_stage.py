"""Several performers on one stage: formations, ensemble variation, the stage file, check --stage.

Formations and variation are pure (checked by their geometry and their monotonicity); the
stage file is read strictly; ``check --stage`` animates every drummer of a four-channel file
(written here, counted independently with mido) on its own kit and holds each one's contacts.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import mido
import numpy as np
import pytest

from livedrummer.stage.formation import Formation, Placement, check_spacing, place
from livedrummer.stage.stagefile import StageError, load_stage
from livedrummer.stage.variation import Variation, bar_edges, gains, vary_rows, warp_times
from services.cli import main


def facing(p: Placement) -> np.ndarray:
    a = math.radians(p.yaw_deg)
    return np.array([-math.sin(a), math.cos(a)])


def test_a_line_is_centred_and_faces_the_audience() -> None:
    spots = place(Formation("line", spacing=2.6), 4)
    assert [round(s.x, 6) for s in spots] == [-3.9, -1.3, 1.3, 3.9]
    assert all(s.y == 0 and s.yaw_deg == 0 for s in spots)


def test_an_arc_keeps_every_drummer_at_the_radius_and_center_facing_looks_inwards() -> None:
    spots = place(Formation("arc", radius=6.0, span_deg=90, spacing=2.0, facing="center"), 5)
    focus = np.array([0.0, -6.0])
    assert all(abs(math.hypot(s.x - focus[0], s.y - focus[1]) - 6.0) < 1e-9 for s in spots)
    cx, cy = np.mean([s.x for s in spots]), np.mean([s.y for s in spots])
    for s in spots:
        to_centre = np.array([cx - s.x, cy - s.y])
        if np.linalg.norm(to_centre) > 1e-9:
            cos = facing(s) @ to_centre / np.linalg.norm(to_centre)
            assert cos > 0.999, (s, cos)


def test_v_grid_and_a_symmetric_explicit_layout() -> None:
    v = place(Formation("v", spacing=2.0), 5)
    assert (v[0].x, v[0].y) == (0.0, 0.0)
    assert [(s.x, s.y) for s in v[1:]] == [(2.0, -2.0), (-2.0, -2.0), (4.0, -4.0), (-4.0, -4.0)]
    grid = place(Formation("grid", spacing=3.0, columns=3), 5)
    assert [round(s.y, 6) for s in grid] == [0, 0, 0, -3, -3]
    assert [round(s.x, 6) for s in grid[3:]] == [-1.5, 1.5]
    sym = place(Formation("explicit", positions=((0, 1), (3, 0)), symmetric=True, facing=20), 3)
    assert [(s.x, s.y, s.yaw_deg) for s in sym] == [(0, 1, 20), (3, 0, 20), (-3, 0, -20)]
    with pytest.raises(ValueError, match="symmetric already"):
        Formation("line", symmetric=True)
    with pytest.raises(ValueError, match=r"1\.30 m apart"):
        check_spacing(place(Formation("line", spacing=1.3), 3), 2.0)


def test_the_warp_wanders_but_keeps_order_downbeats_and_its_bound() -> None:
    edges = bar_edges(np.arange(0, 40, 2.0), 40.0)  # 2 s bars
    t = np.sort(np.random.default_rng(0).uniform(0, 40, 2000))
    for mode in ("bar", "piece"):
        v = Variation(warp_s=0.03, mode=mode, seed=4)
        w = warp_times(t, edges, v)
        assert np.all(np.diff(w) >= 0), mode  # monotonic: hits keep their order
        assert np.abs(w - t).max() <= 0.03 + 1e-12
        assert np.abs(w - t).max() > 0.01  # it does wander
        assert np.array_equal(w, warp_times(t, edges, v))  # seeded: the same show twice
        other = warp_times(t, edges, Variation(warp_s=0.03, mode=mode, seed=5))
        assert not np.allclose(w, other)
    downbeats = edges[:-1]
    assert np.allclose(warp_times(downbeats, edges, Variation(seed=4)), downbeats)
    g = gains(t, edges, Variation(amplitude=0.2, seed=4))
    assert g.min() >= 0.8 - 1e-12 and g.max() <= 1.2 + 1e-12
    assert g.min() < 0.85 and g.max() > 1.15  # reaches the thesis's 1 - R and 1 + R


def write_band(path: Path) -> dict[int, int]:
    """Four drummers on channels 10-13 of one file, each with its own pattern; returns the
    note-on count per channel (1-based), counted here with mido as the independent count."""
    mid = mido.MidiFile(ticks_per_beat=480)
    patterns = {9: (36, 38, 42), 10: (42, 42, 38), 11: (36, 49, 51), 12: (38, 45, 43)}
    counts: dict[int, int] = {}
    for channel, notes in patterns.items():
        track = mido.MidiTrack()
        if channel == 9:
            track.append(mido.MetaMessage("set_tempo", tempo=500_000, time=0))
        for i in range(12 + 3 * (channel - 9)):  # a count of its own per drummer
            note = notes[i % len(notes)]
            track.append(
                mido.Message(
                    "note_on",
                    channel=channel,
                    note=note,
                    velocity=90 + i % 3 * 10,
                    time=0 if i == 0 else 200,
                )
            )
            track.append(mido.Message("note_off", channel=channel, note=note, velocity=0, time=40))
        mid.tracks.append(track)
        counts[channel + 1] = sum(1 for m in track if m.type == "note_on" and m.velocity > 0)
    mid.save(str(path))
    return counts


def test_check_stage_plays_each_channel_on_its_own_kit(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    counts = write_band(tmp_path / "band.mid")
    kits = ["rock5", "rock5-left", "rock5", "rock5-left"]
    performers = "".join(
        f'[[performer]]\nid = "d{ch}"\nfile = "band.mid"\nchannel = {ch}\nmap = "general-midi"\n'
        f'kit = "{kit}"\n\n'
        for ch, kit in zip(counts, kits, strict=True)
    )
    (tmp_path / "stage.toml").write_text(
        '[formation]\nshape = "arc"\nfacing = "center"\n\n' + performers
    )
    assert main(["check", "--stage", str(tmp_path / "stage.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    drummers = out["drummers"]
    assert [d["id"] for d in drummers] == [f"d{ch}" for ch in counts]
    for d, (ch, n) in zip(drummers, counts.items(), strict=True):
        assert d["notes"] == n, (ch, d)  # its own channel's notes, none of another's
        assert d["kit"] == kits[ch - 10]
        assert d["contact_error_mm_max"] <= 5.0 and d["penetration_mm"] <= 2.0, d
    xs = [d["at"][0] for d in drummers]
    assert xs == sorted(xs) and len(set(xs)) == 4  # four places on the arc


def test_an_ensemble_of_one_part_varies_each_copy_and_keeps_contact(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                    groove_files) -> None:  # fmt: skip
    part = groove_files[0]
    (tmp_path / "wall.toml").write_text(
        f'[formation]\nshape = "grid"\ncolumns = 2\n\n[[performer]]\nid = "lead"\n'
        f'file = "{part}"\n\n[ensemble]\ncopies = 3\nwarp_ms = 30\namplitude = 0.2\nseed = 7\n'
    )
    assert main(["check", "--stage", str(tmp_path / "wall.toml"), "--json"]) == 0
    drummers = json.loads(capsys.readouterr().out)["drummers"]
    assert [d["id"] for d in drummers] == ["lead", "lead#2", "lead#3"]
    assert len({d["notes"] for d in drummers}) == 1
    for d in drummers:
        assert d["contact_error_mm_max"] <= 5.0 and d["penetration_mm"] <= 2.0, d


def test_varied_rows_stay_sorted_with_their_controls() -> None:
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file
    from services.cli.files import DEMO_MAP, demo_groove

    perf = read_midi_file(demo_groove(), load_note_map(DEMO_MAP))
    edges = bar_edges(perf.grid.beat_s[perf.grid.beat_in_bar == 0], perf.duration_s)
    on, ctl = vary_rows(perf.onsets, perf.controls, edges, Variation(seed=2))
    assert on.size == perf.onsets.size and ctl.size == perf.controls.size
    assert np.all(np.diff(on["time_s"]) >= 0) and np.all(np.diff(ctl["time_s"]) >= 0)
    assert not np.array_equal(on["velocity"], perf.onsets["velocity"])


@pytest.mark.parametrize(
    ("text", "message"),
    [('[[performer]]\nid = "a"\nfile = "x.mid"\nkitt = "rock5"\n', "[performer 'a'] kitt: unknown key; did you mean 'kit'?"),
     ('[[performer]]\nid = "a"\n', "needs file"),
     ('[[performer]]\nid = "a"\nfile = "x.mid"\n[[performer]]\nid = "a"\nfile = "y.mid"\n', "used twice"),
     ('[formation]\nshape = "circle"\n[[performer]]\nid = "a"\nfile = "x.mid"\n', "shape"),
     ('[[performer]]\nid = "a"\nfile = "x.mid"\nchannel = 17\n', "channel"),
     ("", "no [[performer]]")],
)  # fmt: skip
def test_bad_stage_files_are_one_line_errors(
    tmp_path: Path, capsys, text: str, message: str
) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "stage.toml"
    path.write_text(text)
    with pytest.raises(StageError, match=None) as err:
        load_stage(path)
    assert message in str(err.value) and str(path) in str(err.value)
    assert main(["check", "--stage", str(path)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.usefixtures("gl_ok")
def test_render_stage_draws_every_drummer_in_its_place(tmp_path: Path) -> None:
    import av

    counts = write_band(tmp_path / "band.mid")
    chans = list(counts)[:2]
    (tmp_path / "duo.toml").write_text(
        '[formation]\nshape = "line"\nspacing = 4.0\n\n'
        + "".join(
            f'[[performer]]\nid = "d{c}"\nfile = "band.mid"\nchannel = {c}\n'
            f'map = "general-midi"\n\n'
            for c in chans
        )
    )
    frames = tmp_path / "frames"
    assert (
        main(
            [
                "render",
                "--stage",
                str(tmp_path / "duo.toml"),
                "--frames-dir",
                str(frames),
                "--size",
                "320x180",
                "--fps",
                "4",
                "--tail",
                "0",
                "--camera",
                "front",
            ]
        )
        == 0
    )
    pngs = sorted(frames.glob("*.png"))
    assert len(pngs) >= 4
    with av.open(str(pngs[2])) as c:
        img = next(iter(c.decode(video=0))).to_ndarray(format="rgb24").astype(int)
    lit = img.sum(axis=2) > 120  # drummers and kits under their spots, not the dark stage
    cols = np.flatnonzero(lit.any(axis=0))
    assert cols.size, "nothing drawn"
    left, right = lit[:, :160].sum(), lit[:, 160:].sum()
    assert left > 150 and right > 150, (left, right)  # one drummer on each side
    assert not lit[:, 150:170].any(axis=0).all()  # with a gap between them
    out = tmp_path / "duo.mp4"
    assert (
        main(
            [
                "render",
                "--stage",
                str(tmp_path / "duo.toml"),
                "-o",
                str(out),
                "--size",
                "160x90",
                "--fps",
                "5",
                "--tail",
                "0",
            ]
        )
        == 0
    )
    with av.open(str(out)) as c:
        audio = np.concatenate([f.to_ndarray() for f in c.decode(audio=0)], axis=1)
    assert np.abs(audio).max() > 0.05  # both parts' drum track
