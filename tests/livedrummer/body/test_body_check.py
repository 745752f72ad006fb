"""The physical truth of whole performances: contact, penetration, joint limits, CLI."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.body.check import check, contact_errors
from livedrummer.body.perform import perform
from livedrummer.body.rig import build_rig
from livedrummer.body.sample import sample_poses
from livedrummer.body.skeleton import ARM
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file

REPO = Path(__file__).resolve().parents[3]
DEMO = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"
SCRIPT = Path(sys.executable).parent / "livedrummer"


@pytest.mark.parametrize("kit", ["rock5", "rock5-left"])
def test_demo_groove_lands_every_stroke(kit: str) -> None:
    note_map = load_note_map("roland-td")
    done = perform(read_midi_file(DEMO, note_map), build_rig(load_kit(kit)), note_map)
    r = check(done.animation, done.sticking, fps=120)
    assert r.notes > 700
    assert r.contact_error_m.max() <= 0.005
    assert r.penetration_m <= 0.002
    assert r.joint_limit_violations == 0


def test_contact_error_sees_a_displaced_stick() -> None:
    # the measure itself must be able to fail: shift the right arm's contact keys
    note_map = load_note_map("roland-td")
    done = perform(read_midi_file(DEMO, note_map), build_rig(load_kit("rock5")), note_map)
    curve = done.animation.arms["r"][ARM["R"][2]]
    curve.rotvec[:] += np.array([0.05, 0.0, 0.0])
    played, err = contact_errors(done.animation, done.sticking)
    right = done.sticking.limb[played] == 0
    assert err[right].min() > 0.005
    assert err[~right & (done.sticking.limb[played] == 1)].max() < 1e-6


def test_poses_carry_kit_channels() -> None:
    note_map = load_note_map("roland-td")
    rig = build_rig(load_kit("rock5"))
    done = perform(read_midi_file(DEMO, note_map), rig, note_map)
    t = np.arange(0.0, 20.0, 1 / 60)
    poses = sample_poses(done.animation, done.sticking, t, done.chokes)
    names = [p.name for p in rig.kit.pieces]
    assert poses.dtype["swing"].shape == (len(names),)
    assert np.abs(poses["swing"][:, names.index("kick")]).max() > 0.1  # the beater moves
    assert poses["glow"][:, names.index("snare")].max() > 0.3
    assert np.isfinite(poses["position"]).all()


def test_check_cli_json_fields() -> None:
    command = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "services"]
    res = subprocess.run(
        [
            *command,
            "check",
            str(DEMO),
            "--map",
            "roland-td",
            "--kit",
            "rock5-left",
            "--json",
            "--fps",
            "60",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=dict(os.environ),
        check=False,
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["notes"] > 700
    assert set(out["contact_error_mm"]) >= {"max", "p99", "mean"}
    assert out["contact_error_mm"]["max"] <= 5.0
    assert out["penetration_mm"] <= 2.0
    assert isinstance(out["joint_limit_violations"], int)


@pytest.mark.parametrize("kit", ["rock5", "rock5-left"])
def test_corpus_sample_lands(groove_files: list[Path], kit: str) -> None:
    """CORPUS test (about 15 s per kit): every 40th Groove file; ``livedrummer check
    ../shared/data/groove`` gives the whole-corpus figure."""
    note_map = load_note_map("roland-td")
    rig = build_rig(load_kit(kit))
    worst_contact, worst_depth = 0.0, 0.0
    for path in groove_files[::40]:
        done = perform(read_midi_file(path, note_map), rig, note_map)
        r = check(done.animation, done.sticking, fps=60)
        if r.contact_error_m.size:
            worst_contact = max(worst_contact, float(r.contact_error_m.max()))
        worst_depth = max(worst_depth, r.penetration_m)
    assert worst_contact <= 0.005
    assert worst_depth <= 0.002


def test_short_arm_chain_matches_full_forward_kinematics() -> None:
    from livedrummer.body.animation import arm_tip

    note_map = load_note_map("roland-td")
    done = perform(read_midi_file(DEMO, note_map), build_rig(load_kit("rock5-left")), note_map)
    t = np.linspace(0.0, 30.0, 400)
    _, _, _, wp = done.animation.solve(t, guard=False)
    for side in "rl":
        np.testing.assert_allclose(
            arm_tip(done.animation, side, t), wp[:, ARM[side.upper()][4]], atol=1e-12
        )
