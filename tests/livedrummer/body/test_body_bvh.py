"""BVH export, read back by an independent parser whose own FK must match ours."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from livedrummer.body import fk
from livedrummer.body.bvh import bvh_text
from livedrummer.body.perform import perform
from livedrummer.body.rig import build_rig
from livedrummer.body.skeleton import JOINTS
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file

REPO = Path(__file__).resolve().parents[3]
DEMO = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


def read_bvh(text: str) -> tuple[dict[str, np.ndarray], float]:
    """A from-scratch BVH reader: returns world positions (cm, BVH frame) of every joint and
    end site per frame, named ``joint`` or ``parent/end``; and the frame time."""
    tokens = text.split()
    pos = 0
    nodes: list[dict] = []  # name, parent, offset, channels

    def take() -> str:
        nonlocal pos
        pos += 1
        return tokens[pos - 1]

    assert take() == "HIERARCHY"
    stack: list[int] = []
    pending: str | None = None
    while True:
        tok = take()
        if tok in ("ROOT", "JOINT"):
            pending = take()
        elif tok == "End":
            assert take() == "Site"
            pending = nodes[stack[-1]]["name"] + "/end"
        elif tok == "{":
            nodes.append(
                {
                    "name": pending,
                    "parent": stack[-1] if stack else -1,
                    "offset": None,
                    "channels": [],
                }
            )
            stack.append(len(nodes) - 1)
        elif tok == "OFFSET":
            nodes[stack[-1]]["offset"] = np.array([float(take()) for _ in range(3)])
        elif tok == "CHANNELS":
            nodes[stack[-1]]["channels"] = [take() for _ in range(int(take()))]
        elif tok == "}":
            stack.pop()
        elif tok == "MOTION":
            break
    assert take() == "Frames:"
    frames = int(take())
    assert take() == "Frame" and take() == "Time:"
    frame_time = float(take())
    width = sum(len(n["channels"]) for n in nodes)
    data = np.array([float(x) for x in tokens[pos:]]).reshape(frames, width)

    def axis_matrix(axis: str, deg: float) -> np.ndarray:
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        if axis == "X":
            return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
        if axis == "Y":
            return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

    out = {n["name"]: np.zeros((frames, 3)) for n in nodes}
    for f in range(frames):
        col = 0
        world_r: list[np.ndarray] = []
        world_p: list[np.ndarray] = []
        for n in nodes:
            r = np.eye(3)
            p = n["offset"].copy()
            for ch in n["channels"]:
                v = data[f, col]
                col += 1
                if ch.endswith("position"):
                    p["XYZ".index(ch[0])] += v
                else:
                    r = r @ axis_matrix(ch[0], v)
            if n["parent"] >= 0:
                pr, pp = world_r[n["parent"]], world_p[n["parent"]]
                p = pp + pr @ p
                r = pr @ r
            world_r.append(r)
            world_p.append(p)
            out[n["name"]][f] = p
    return out, frame_time


def test_independent_reader_matches_our_forward_kinematics() -> None:
    note_map = load_note_map("roland-td")
    rig = build_rig(load_kit("rock5-left"))
    perf = read_midi_file(DEMO, note_map)
    done = perform(perf, rig, note_map)
    times = np.linspace(2.0, 6.0, 37)
    local, root = done.animation.locals(times)
    _, ours = fk.forward(rig.skeleton, local, root)
    got, frame_time = read_bvh(bvh_text(rig.skeleton, local, root, 30.0))
    assert abs(frame_time - 1 / 30) < 1e-8
    m = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])
    ends = {
        "head_top": "head/end",
        "r_tip": "r_stick/end",
        "l_tip": "l_stick/end",
        "r_toe": "r_ankle/end",
        "l_toe": "l_ankle/end",
    }
    for j, name in enumerate(JOINTS):
        theirs = got[ends.get(name, name)]
        np.testing.assert_allclose(theirs, ours[:, j] @ m.T * 100.0, atol=2e-3, err_msg=name)


def test_export_cli_writes_a_bvh(tmp_path: Path) -> None:
    out = tmp_path / "drummer.bvh"
    script = Path(sys.executable).parent / "livedrummer"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "services"]
    res = subprocess.run(
        [*command, "export", str(DEMO), "-o", str(out), "--map", "roland-td", "--fps", "24"],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    text = out.read_text()
    frames = int(re.search(r"Frames: (\d+)", text).group(1))  # type: ignore[union-attr]
    assert frames > 24 * 60  # the groove lasts more than a minute
    assert len(text.split("MOTION")[1].strip().splitlines()) == frames + 2
