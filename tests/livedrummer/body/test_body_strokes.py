"""Stroke keyframes and splines: the seeds' behaviours, pinned."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from livedrummer.body import spline
from livedrummer.body.animation import FOOT_LIFT_M, Openness, animate
from livedrummer.body.rig import build_rig
from livedrummer.body.skeleton import ARM, LEG
from livedrummer.body.strokes import (
    AFTER,
    BEFORE,
    CONTACT,
    MERGED,
    TRAVEL,
    StrokeParams,
    lagged_times,
    stroke_keys,
)
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENT_CODE, ZONES, HiHat, Limb, Zone
from livedrummer.sticking.result import LIMB_CODE, Sticking
from livedrummer.timeline.events import ONSET_DTYPE

P = StrokeParams()


def keys_for(times: list[float], ids: list[int], vel: float = 1.0, el: float = 0.5,
             params: StrokeParams = P, pieces: list[int] | None = None):  # type: ignore[no-untyped-def]  # fmt: skip
    n = len(times)
    return stroke_keys(
        np.array(times),
        np.array(ids),
        np.full(n, vel),
        np.full(n, el),
        params,
        None if pieces is None else np.array(pieces),
    )


def test_single_stroke_before_contact_after() -> None:
    k = keys_for([1.0], [0], vel=0.8, el=0.5)
    assert k.kind.tolist() == [BEFORE, CONTACT, AFTER]
    np.testing.assert_allclose(k.time_s, [1.0 - P.delta_s / 2, 1.0, 1.0 + P.delta_s / 2])
    # paper: before = DOWN + vel*diff, after = DOWN + vel*el*diff
    np.testing.assert_allclose(k.lift, [0.8, 0.0, 0.8 * 0.5])


def test_elasticity_zero_rebound_equals_contact() -> None:
    k = keys_for([1.0], [0], vel=1.0, el=0.0)
    assert k.lift[k.kind == AFTER][0] == 0.0


def test_same_piece_overlap_merges_nearer_down_when_closer() -> None:
    far = keys_for([1.0, 1.0 + 0.08], [3, 3])
    near = keys_for([1.0, 1.0 + 0.04], [3, 3])
    for k, gap in ((far, 0.08), (near, 0.04)):
        assert k.kind.tolist() == [BEFORE, CONTACT, MERGED, CONTACT, AFTER]
        assert k.time_s[2] == pytest.approx(1.0 + gap / 2)
    assert 0 < near.lift[2] < far.lift[2]
    # the merged key's lift is proportional to the gap (fig. 7 / SMED fig. 4.10)
    assert near.lift[2] / far.lift[2] == pytest.approx(0.5)


def test_no_overlap_keeps_both_strokes() -> None:
    k = keys_for([1.0, 1.0 + 0.3], [3, 3])
    assert k.kind.tolist() == [BEFORE, CONTACT, AFTER, BEFORE, CONTACT, AFTER]


def test_different_pieces_shorten_travel_to_fraction_a() -> None:
    gap = 0.06
    for a in (0.3, 0.6):
        k = keys_for([1.0, 1.0 + gap], [1, 2], params=StrokeParams(fraction_a=a, model="paper"))
        assert k.kind.tolist() == [BEFORE, CONTACT, AFTER, BEFORE, CONTACT, AFTER]
        after, before = k.time_s[2], k.time_s[3]
        assert before - after == pytest.approx(a * gap)
        assert after - 1.0 == pytest.approx((1 - a) * gap / 2)
        # the paper does not attenuate
        assert k.lift[2] == pytest.approx(0.5) and k.lift[3] == pytest.approx(1.0)


def test_close_notes_attenuate_and_travel_arc_between_pieces() -> None:
    slow = keys_for([1.0, 1.09], [1, 2], pieces=[1, 2])
    fast = keys_for([1.0, 1.03], [1, 2], pieces=[1, 2])
    for k in (slow, fast):
        assert k.kind.tolist() == [BEFORE, CONTACT, AFTER, TRAVEL, BEFORE, CONTACT, AFTER]
    assert fast.lift[4] < slow.lift[4] <= 1.0  # before of the 2nd note attenuated
    assert fast.lift[4] >= P.travel_lift
    assert slow.lift[3] > max(slow.lift[2], slow.lift[4])  # the arc rises above both


def test_smed_model_merges_any_overlap() -> None:
    k = keys_for([1.0, 1.05], [1, 2], params=StrokeParams(model="smed"))
    assert k.kind.tolist() == [BEFORE, CONTACT, MERGED, CONTACT, AFTER]


def test_keys_are_time_ordered_for_dense_random_notes() -> None:
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.03, 0.4, 400))
    ids = rng.integers(0, 3, 400)
    k = stroke_keys(t, ids, rng.uniform(0, 1, 400), rng.uniform(0, 1, 400), P, ids)
    assert np.all(np.diff(k.time_s) >= 0)
    for scale in (1.0, 0.6, 0.2):
        assert np.all(np.diff(lagged_times(k, scale)) >= 0)
    np.testing.assert_array_equal(k.time_s[k.kind == CONTACT], t)


def test_ctb_passes_through_keys_with_a_corner_at_contact() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.5])
    v = np.array([1.0, 0.0, 0.6, 0.6])
    tension = np.array([1.0, 0.0, 1.0, 1.0])
    cont = np.array([0.0, -1.0, 0.0, 0.0])
    np.testing.assert_allclose(spline.evaluate(t, v, t, tension, cont), v, atol=1e-12)
    eps = 1e-6
    left = (
        spline.evaluate(t, v, np.array([0.1]), tension, cont)
        - spline.evaluate(t, v, np.array([0.1 - eps]), tension, cont)
    ) / eps
    right = (
        spline.evaluate(t, v, np.array([0.1 + eps]), tension, cont)
        - spline.evaluate(t, v, np.array([0.1]), tension, cont)
    ) / eps
    assert left[0] < 0 < right[0]  # the stick reverses at impact
    dense = spline.evaluate(t, v, np.linspace(0, 0.5, 2001), tension, cont)
    assert dense.min() >= -1e-12  # never below the contact value


def test_smooth_ctb_is_catmull_rom_on_uniform_keys() -> None:
    t = np.arange(5.0)
    v = np.array([0.0, 1.0, 0.0, 2.0, 1.0])
    mid = spline.evaluate(t, v, np.array([1.5]))
    # uniform Catmull-Rom midpoint: (-p0 + 9 p1 + 9 p2 - p3) / 16
    assert mid[0] == pytest.approx((-0.0 + 9 * 1.0 + 9 * 0.0 - 2.0) / 16)


# --- through the whole body ---------------------------------------------------------------


def _sticking(kit: Kit, notes: list[tuple[float, str, Zone, int, Limb]]) -> Sticking:
    on = np.zeros(len(notes), dtype=ONSET_DTYPE)
    names = [p.name for p in kit.pieces]
    for i, (t, piece, zone, vel, _) in enumerate(notes):
        on[i] = (
            t,
            38,
            vel,
            9,
            INSTRUMENT_CODE[kit.piece(piece).plays[0]],
            ZONES.index(zone),
            HIHATS.index(HiHat.NONE),
            np.nan,
            0,
        )
    limb = np.array([LIMB_CODE[n[4]] for n in notes], dtype=np.int8)
    piece_idx = np.array([names.index(n[1]) for n in notes], dtype=np.int16)
    return Sticking(on, limb, piece_idx, {}, "test", kit.name)


def _tip_height_above_snare(kit: Kit, vel: int, at: float) -> float:
    rig = build_rig(kit)
    st = _sticking(kit, [(1.0, "snare", Zone.HEAD, vel, Limb.LH)])
    anim = animate(rig, st, np.zeros(0), Openness(np.zeros(0), np.zeros(0)))
    _, wp = anim.world(np.array([at]))
    snare = kit.piece("snare")
    return float(np.dot(wp[0, ARM["L"][4]] - np.asarray(snare.position_m), snare.normal))


def test_preparation_height_grows_with_velocity() -> None:
    kit = load_kit("rock5")
    # at the preparation key, δ/2 before the contact (earlier the hand waits ready, the same
    # whatever the velocity: livedrummer.body.ready)
    heights = [_tip_height_above_snare(kit, v, 0.95) for v in (20, 60, 100, 127)]
    assert all(b > a + 0.01 for a, b in itertools.pairwise(heights))
    assert _tip_height_above_snare(kit, 100, 1.0) == pytest.approx(0.0, abs=1e-9)


def test_zero_elasticity_body_rebound_stays_on_the_head() -> None:
    kit = load_kit("rock5")
    dead = dataclasses.replace(kit.piece("snare"), elasticity=0.0)
    dull = Kit(
        kit.name,
        "",
        "right",
        kit.seat_height_m,
        tuple(dead if p.name == "snare" else p for p in kit.pieces),
    )
    # at the rebound (the stick's key, the earliest of the lagged ones: later the hand rises
    # into its ready wait, livedrummer.body.ready)
    assert _tip_height_above_snare(dull, 110, 1.03) == pytest.approx(0.0, abs=1e-9)
    assert _tip_height_above_snare(kit, 110, 1.05) > 0.05


def test_whip_lag_stick_behind_wrist_behind_elbow() -> None:
    kit = load_kit("rock5")
    rig = build_rig(kit)
    st = _sticking(kit, [(1.0, "snare", Zone.HEAD, 110, Limb.LH)])
    anim = animate(rig, st, np.zeros(0), Openness(np.zeros(0), np.zeros(0)))
    curves = anim.arms["l"]
    _sh, el, wr, sk, _ = ARM["L"]
    # the preparation and rebound keys, inside the ready keys (livedrummer.body.ready) that
    # wait before and after the note
    first = {j: curves[j].time_s[1] for j in (el, wr, sk)}
    assert first[el] < first[wr] < first[sk] < 1.0  # downswing starts at the elbow
    last = {j: curves[j].time_s[-2] for j in (el, wr, sk)}
    assert 1.0 < last[sk] < last[wr] < last[el]


def test_hihat_foot_follows_the_pedal_controller_and_kick_foot_strokes() -> None:
    kit = load_kit("rock5")
    rig = build_rig(kit)
    st = _sticking(
        kit,
        [(1.0, "hihat", Zone.BOW, 90, Limb.RH), (2.0, "kick", Zone.HEAD, 120, Limb.RF)],
    )
    openness = Openness(np.array([0.0, 1.5]), np.array([0.0, 0.8]))
    anim = animate(rig, st, np.zeros(0), openness)
    t = np.array([1.0, 1.8])
    np.testing.assert_allclose(anim.foot_lift("l", t), [0.0, 0.8])
    _, wp = anim.world(t)
    toe = wp[:, LEG["L"][3]]
    assert toe[1, 2] - toe[0, 2] == pytest.approx(FOOT_LIFT_M * 0.8)
    # the kick foot is on its footboard at the onset and up before it
    lift = anim.foot_lift("r", np.array([1.9, 2.0]))
    assert lift[0] > 0.5 and lift[1] == pytest.approx(0.0, abs=1e-12)
