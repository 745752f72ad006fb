"""Reaching the drums: every zone of every piece, on any kit, from the geometry alone."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from livedrummer.body.ik import solve_arm, solve_leg
from livedrummer.body.rig import build_rig, neutral_world
from livedrummer.body.skeleton import J, build_skeleton
from livedrummer.body.targets import HIHAT_MAX_LIFT_M, target_table, zone_target
from livedrummer.errors import UnreachableError
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import ZONES, Limb, PieceKind, Zone


def _surface_distance(piece: Piece, point: np.ndarray) -> float:
    return float(np.dot(point - np.asarray(piece.position_m), piece.normal))


@pytest.mark.parametrize("name", ["rock5", "rock5-left"])
def test_targets_lie_on_the_surface_inside_the_disc(name: str) -> None:
    kit = load_kit(name)
    for piece in kit.pieces:
        for zone in piece.zones:
            t = zone_target(piece, zone)
            if t.is_pedal:
                continue
            assert abs(_surface_distance(piece, t.point)) < 1e-12
            radial = np.linalg.norm(t.point - np.asarray(piece.position_m))
            assert radial <= piece.radius_m + 1e-12


def test_cymbal_zones_order_bell_bow_edge_and_hihat_lifts() -> None:
    kit = load_kit("rock5")
    ride = kit.piece("ride")
    r = {
        z: np.linalg.norm(zone_target(ride, z).point - np.asarray(ride.position_m))
        for z in (Zone.BELL, Zone.BOW, Zone.EDGE)
    }
    assert r[Zone.BELL] < r[Zone.BOW] < r[Zone.EDGE] <= ride.radius_m
    table = target_table(kit)
    hat = [p.name for p in kit.pieces].index("hihat")
    closed, _, _ = table.lookup(np.array([hat]), np.array([Zone.BOW.code]), np.array([0.0]))
    opened, _, _ = table.lookup(np.array([hat]), np.array([Zone.BOW.code]), np.array([1.0]))
    assert np.dot(opened[0] - closed[0], kit.piece("hihat").normal) == pytest.approx(
        HIHAT_MAX_LIFT_M
    )


@pytest.mark.parametrize("name", ["rock5", "rock5-left"])
def test_every_hand_zone_reached_exactly_by_both_arms(name: str) -> None:
    rig = build_rig(load_kit(name))
    skel = rig.skeleton
    wq, wp = neutral_world(skel, 10.0)
    for k, (side, sign) in enumerate((("r", 1.0), ("l", -1.0))):
        for i, piece in enumerate(rig.kit.pieces):
            for zone in piece.zones:
                if rig.targets.is_pedal[i, zone.code]:
                    continue
                point, normal, pitch = rig.targets.lookup(np.array([i]), np.array([zone.code]))
                sol = solve_arm(
                    skel.lengths,
                    wp[:, J[f"{side}_shoulder"]],
                    wq[:, J["chest"]],
                    sign,
                    point,
                    normal,
                    pitch,
                )
                assert rig.hand_ok[k, i, zone.code]
                assert np.linalg.norm(sol.tip[0] - point[0]) < 1e-9
                # bones keep their lengths
                s = skel.lengths
                assert np.linalg.norm(sol.elbow - wp[:, J[f"{side}_shoulder"]]) == (
                    pytest.approx(s.upper_arm)
                )
                assert np.linalg.norm(sol.wrist - sol.elbow) == pytest.approx(s.forearm)
                # the stick comes down onto the surface from above, not through it
                assert np.dot(sol.fulcrum[0] - point[0], normal[0]) > 0


def test_mirrored_kit_gives_mirrored_reach() -> None:
    right = build_rig(load_kit("rock5"))
    left = build_rig(load_kit("rock5-left"))
    np.testing.assert_array_equal(right.hand_ok[0], left.hand_ok[1])
    np.testing.assert_allclose(right.hand_gap_m[0], left.hand_gap_m[1], atol=1e-9)


def test_feet_rest_on_their_pedals() -> None:
    kit = load_kit("rock5")
    skel = build_skeleton(seat_height_m=kit.seat_height_m)
    for piece, side in ((kit.piece("kick"), "r"), (kit.piece("hihat"), "l")):
        hip = (skel.root_m + skel.offsets[J[f"{side}_hip"]])[None]
        toe = np.asarray(piece.pedal_position_m)[None]
        leg = solve_leg(skel.lengths, hip, toe)
        assert leg.reached[0]
        np.testing.assert_allclose(leg.toe, toe, atol=1e-9)
        assert leg.knee[0, 1] > hip[0, 1]  # the knee points forward


def test_unreachable_piece_is_a_named_error_at_load() -> None:
    kit = load_kit("rock5")
    far = dataclasses.replace(kit.piece("crash2"), position_m=(1.6, 1.4, 1.9))
    pieces = tuple(far if p.name == "crash2" else p for p in kit.pieces)
    bad = Kit(
        kit.name, kit.description, kit.handedness, kit.seat_height_m, pieces, source="test-kit.toml"
    )
    with pytest.raises(UnreachableError, match=r"test-kit.toml.*'crash2'.*RH stick by \d+ mm"):
        build_rig(bad)


def test_unreachable_pedal_is_a_named_error() -> None:
    kit = load_kit("rock5")
    far = dataclasses.replace(kit.piece("kick"), pedal_position_m=(0.1, 1.5, 0.02))
    pieces = tuple(far if p.name == "kick" else p for p in kit.pieces)
    bad = Kit(kit.name, kit.description, kit.handedness, kit.seat_height_m, pieces)
    with pytest.raises(UnreachableError, match=r"pedal of 'kick'.*RF foot"):
        build_rig(bad)


@settings(max_examples=25, deadline=None)
@given(
    x=st.floats(-0.5, 0.5), y=st.floats(0.3, 0.7), z=st.floats(0.55, 1.2),
    tilt=st.floats(0.0, 25.0), facing=st.floats(-40.0, 40.0), cymbal=st.booleans(),
)  # fmt: skip
def test_a_users_piece_in_reach_is_hit_exactly(
    x: float, y: float, z: float, tilt: float, facing: float, cymbal: bool
) -> None:
    kind = PieceKind.RIDE if cymbal else PieceKind.TOM
    zones = (Zone.BOW, Zone.EDGE, Zone.BELL) if cymbal else (Zone.HEAD, Zone.RIM)
    piece = Piece(
        "mine",
        kind,
        (x, y, z),
        0.15,
        0.0 if cymbal else 0.2,
        tilt,
        facing,
        zones,
        ("tom1",),
        Limb.RH,
        0.1,
        0.5,
    )
    kit = Kit("user", "", "right", 0.52, (piece,))
    skel = build_skeleton(seat_height_m=0.52)
    _, wp = neutral_world(skel, 10.0)
    shoulder = wp[0, J["r_shoulder"]]
    near = all(
        np.linalg.norm(zone_target(piece, zone).point - shoulder) < 0.9 * skel.arm_reach
        for zone in zones
    )
    try:
        rig = build_rig(kit)
    except UnreachableError:
        assert not near  # a refusal only when some target is really far
        return
    for zone in zones:
        assert rig.hand_ok[0, 0, ZONES.index(zone)]
