"""The strike solve's foot table: a foot's contact looked up is the contact solved."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer.body.pose import pose_dtype
from livedrummer.body.rig import build_rig
from livedrummer.body.skeleton import LEG, N_JOINTS
from livedrummer.body.strike import foot_contacts, footboard, strike_poses
from livedrummer.kit.loader import load_kit


@pytest.mark.parametrize("name", ["rock5", "rock5-left"])
def test_a_foot_looked_up_is_the_foot_solved_on_every_piece(name: str) -> None:
    rig = build_rig(load_kit(name))
    feet = foot_contacts(rig)
    n = len(rig.kit.pieces)
    rng = np.random.default_rng(3)
    base = np.zeros(n, pose_dtype(n))
    base["rotation"] = rng.normal(size=(n, N_JOINTS, 4))  # any body: the foot ignores it
    base["position"] = rng.normal(size=(n, N_JOINTS, 3))
    piece = np.arange(n)
    zone, velocity, openness = np.zeros(n, np.int64), np.full(n, 90.0), np.full(n, np.nan)
    for limb in (2, 3):
        solved = strike_poses(rig, base, limb, piece, zone, velocity, openness)
        looked = strike_poses(rig, base, limb, piece, zone, velocity, openness, feet)
        for field in ("rotation", "position", "glow", "swing"):
            np.testing.assert_allclose(looked[field], solved[field], rtol=0, atol=1e-6)
        # only the leg moved, and its toe is on each piece's footboard
        toe = LEG["R" if limb == 2 else "L"][3]
        boards = np.array([footboard(rig, k) for k in range(n)])
        reached = np.linalg.norm(looked["position"][:, toe] - boards, axis=-1) < 1e-4
        assert reached[[k for k, pc in enumerate(rig.kit.pieces) if pc.pedal_position_m]].all()
        other = np.setdiff1d(np.arange(N_JOINTS), LEG["R" if limb == 2 else "L"])
        np.testing.assert_array_equal(looked["rotation"][:, other], base["rotation"][:, other])
