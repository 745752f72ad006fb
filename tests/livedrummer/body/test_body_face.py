"""The face (:mod:`livedrummer.body.face`): blinks, reactions to accents and crashes, the
eyes' look; the shapes that draw it (the built-in character's, a VRM's expressions); the GPU."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import avatar_files as af
import numpy as np
import pytest

from livedrummer.avatar.character import build_character
from livedrummer.avatar.fit import scaled_avatar
from livedrummer.avatar.loader import load_avatar_file
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.face import (
    FACES,
    FaceParams,
    FaceTrack,
    Reactions,
    blink_times,
    blink_weight,
)
from livedrummer.body.skeleton import N_JOINTS, J
from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.kitmesh import build_kit_mesh, empty_stage
from livedrummer.render.scene import CH_HIGHLIGHT

P = FaceParams()


def test_blinks_come_at_natural_intervals() -> None:
    t = blink_times(0.0, 1800.0, P)
    gaps = np.diff(t)
    per_minute = t.size / 30.0
    assert 12.0 <= per_minute <= 20.0  # people blink some 15 times a minute
    assert gaps.min() >= P.blink_range_s[0] - 1e-9
    assert gaps.max() <= P.blink_range_s[1] + P.blink_range_s[0]
    assert 3.0 <= float(np.median(gaps)) <= 4.5
    assert np.percentile(gaps, 90) > 1.6 * np.median(gaps)  # irregular, not a metronome


def test_blinks_are_the_same_for_a_seed_whatever_window_asks() -> None:
    whole = blink_times(-30.0, 300.0, P)
    parts = np.concatenate([blink_times(a, a + 7.3, P) for a in np.arange(-30.0, 300.0, 7.3)])
    np.testing.assert_array_equal(whole, parts[parts < 300.0])
    other = blink_times(-30.0, 300.0, dataclasses.replace(P, seed=1))
    assert not np.array_equal(whole, other)
    times = np.arange(0.0, 60.0, 1 / 240)
    w = blink_weight(times, P)
    np.testing.assert_array_equal(w[::8], blink_weight(times[::8], P))  # 30 fps as 240 fps
    shut = times[w > 0.99]
    assert shut.size and np.all((w >= 0) & (w <= 1))
    starts = blink_times(0.0, 60.0, P)
    assert np.all(np.abs(shut[:, None] - starts[None, :]).min(axis=1) < 0.1)
    assert (w > 0.5).mean() < 0.05  # the eyes are open nearly all the time


def _glow(hits: list[tuple[float, int, float]], times: np.ndarray, pieces: int) -> np.ndarray:
    g = np.zeros((times.size, pieces))
    for at, piece, v in hits:
        on = times >= at
        g[on, piece] = v * np.exp(-(times[on] - at) / 0.15)
    return g


@pytest.mark.parametrize("fps", [30.0, 60.0])
def test_a_crash_surprises_an_accent_pleases_a_soft_hit_leaves_the_face_alone(fps: float) -> None:
    crash = np.array([False, True])  # piece 0 a snare, piece 1 a crash
    times = np.arange(0.0, 4.0, 1 / fps)
    hits = [(0.5, 1, 0.9), (2.0, 0, 0.95), (3.0, 0, 0.4), (3.02, 1, 0.3)]
    glow = _glow(hits, times, 2)
    r = Reactions(crash)
    out = np.array([r.update(float(t), g) for t, g in zip(times, glow, strict=True)])
    happy, surprised = out[:, 0], out[:, 1]

    def at(t: float) -> int:
        return int(np.searchsorted(times, t - 1e-9))

    assert surprised[at(0.5) + 1] == pytest.approx(1.0)  # within a frame of the crash
    assert surprised[at(0.8)] > 0.5 and surprised[at(1.2)] == 0.0
    assert happy[at(2.0) + 1] == pytest.approx(1.0) and happy[at(2.3)] > 0.5
    assert out[at(2.8) :].max() == 0.0  # soft hits: nothing
    assert happy[: at(2.0)].max() == 0.0  # a crash surprises, it does not please
    r.update(0.0, glow[0])  # back in time (a seek): starts afresh
    assert r.update(0.01, glow[0]) == (0.0, 0.0)


def test_30_and_60_fps_draw_the_same_reaction() -> None:
    crash = np.array([False, True])
    hits = [(0.5, 1, 0.9), (2.0, 0, 0.95)]
    out = {}
    for fps in (30.0, 60.0):
        times = np.arange(0.0, 3.0, 1 / fps)
        r = Reactions(crash)
        got = [r.update(float(t), g) for t, g in zip(times, _glow(hits, times, 2), strict=True)]
        out[fps] = (times, np.array(got))
    t30, w30 = out[30.0]
    _, w60 = out[60.0]
    assert np.abs(w60[::2][: len(t30)] - w30).max() < 0.15  # one frame's timing apart at most


@pytest.fixture(scope="module")
def faces_vrm(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("faces")
    return {
        v: af.write(
            folder, f"faces{v}.vrm", af.Spec(height_m=1.75, pose="A", facing=f, vrm=v, faces=True)
        )
        for v, f in (("0", "-z"), ("1", "+z"))
    }


@pytest.mark.parametrize("version", ["0", "1"])
def test_a_vrms_expressions_become_its_face(faces_vrm: dict[str, Path], version: str) -> None:
    a = load_avatar_file(faces_vrm[version])
    assert set(a.faces) == {"blink", "happy", "surprised"}  # the file has no look expressions
    head = a.faces["blink"].vertices
    assert head.size == 24  # the head's boxes (face, nose, hair: 3 x 8 corners)
    np.testing.assert_allclose(
        a.faces["blink"].deltas, np.tile([0.0, 0.0, -0.01], (24, 1)), atol=1e-6
    )
    # joy/happy is bound at half weight; the file's +x is the character's left, our -x
    want = 0.5 * 0.02 * (-1.0 if version == "1" else 1.0)
    np.testing.assert_allclose(a.faces["happy"].deltas[:, 0], want, atol=1e-6)
    big = scaled_avatar(a, 2.0)
    np.testing.assert_allclose(big.faces["blink"].deltas, 2.0 * a.faces["blink"].deltas)
    plain = load_avatar_file(af.write(faces_vrm["0"].parent, "plain.vrm", af.Spec(vrm=version)))
    assert plain.faces == {}


def test_the_built_in_character_has_every_face() -> None:
    c = build_character()
    assert set(c.faces) == set(FACES)
    for name, f in c.faces.items():
        assert f.vertices.size and 0.002 < float(np.abs(f.deltas).max()) < 0.02, name
    blink = c.faces["blink"]  # the eyes flatten: their vertical spread shrinks
    before = np.ptp(c.mesh.positions[blink.vertices, 2])
    after = np.ptp(c.mesh.positions[blink.vertices, 2] + blink.deltas[:, 2])
    assert after < 0.5 * before


@pytest.fixture(scope="module")
def ctx() -> Any:
    from services.display.context import DisplayError, headless_context

    try:
        return headless_context()
    except DisplayError as exc:
        pytest.skip(str(exc))


def test_the_gpu_draws_the_face_shapes(ctx: Any, faces_vrm: dict[str, Path]) -> None:
    from services.display.avatar_gl import SkinnedDraw
    from services.display.renderer import Renderer

    r = Renderer(ctx, empty_stage(), BODY_SKELETON, (64, 64), samples=0)
    for avatar in (build_character(), load_avatar_file(faces_vrm["1"])):
        draw = SkinnedDraw(ctx, r.programs["skin"], avatar)
        q = quat.identity((N_JOINTS,)).astype(np.float32)
        p = avatar.mesh.bind[:, :3, 3].copy()
        rest = draw.skinned_positions(q, p)
        weights = {"blink": 1.0, "happy": 0.5}
        draw.set_face(weights)
        got = draw.skinned_positions(q, p)
        moved = avatar.mesh.positions.astype(np.float64).copy()
        for name, w in weights.items():
            moved[avatar.faces[name].vertices] += w * avatar.faces[name].deltas
        shaped = dataclasses.replace(avatar.mesh, positions=moved.astype(np.float32))
        cpu = skin(shaped, skin_matrices(joint_matrices(q, p), avatar.mesh.bind))[0]
        assert np.abs(got - cpu).max() < 1e-5
        assert np.abs(got - rest).max() > 0.004
        draw.set_face({})
        assert np.abs(draw.skinned_positions(q, p) - rest).max() < 1e-6


def test_a_render_blinks_and_reacts(tmp_path: Path) -> None:
    """Frames of a crash at 1.0 s (velocity 120) drawn in order, as the renderer draws them:
    the face is surprised just after it, and blinks where the schedule says."""
    from livedrummer.midi.smf import read_midi_file

    kit = load_kit("rock5")
    song = tmp_path / "crash.mid"
    _crash_file(song)
    note_map = load_note_map("general-midi")
    scene = BodyScene.perform(read_midi_file(song, note_map), kit, note_map)
    track_ = FaceTrack(build_kit_mesh(kit).crash_like)
    times = np.arange(0.0, 3.0, 1 / 30)
    faces = []
    for t in times:
        f = scene.frame_at(float(t))
        assert f.rotations_q is not None
        faces.append(
            track_.weights(float(t), f.channels[:, CH_HIGHLIGHT], f.rotations_q[J["head"]])
        )
    surprised = np.array([w["surprised"] for w in faces])
    assert surprised[times < 0.99].max() == 0.0
    assert surprised[(times > 1.0) & (times < 1.2)].min() > 0.9
    blink = np.array([w["blink"] for w in faces])
    np.testing.assert_allclose(blink, blink_weight(times, P))
    looks = np.array([[w[k] for k in ("look_left", "look_right")] for w in faces])
    assert looks.max() > 0.1  # the eyes do turn


def _crash_file(path: Path) -> None:
    import mido

    mid = mido.MidiFile(ticks_per_beat=480)
    track = mido.MidiTrack()
    last = 0
    for tick, note, vel in (
        (0, 42, 60),
        (480, 42, 60),
        (960, 49, 120),
        (960, 36, 100),
        (1440, 42, 60),
        (1920, 38, 60),
    ):
        track.append(mido.Message("note_on", channel=9, note=note, velocity=vel, time=tick - last))
        track.append(mido.Message("note_off", channel=9, note=note, velocity=0, time=0))
        last = tick
    mid.tracks.append(track)
    mid.save(path)
