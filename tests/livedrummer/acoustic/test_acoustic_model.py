"""The learned hit classifier: the shipped model on a kit it never heard, training, the file.

The bundled model (``kits/audio/acoustic-model.npz``) is trained without the named held-out
set, TimGM6mb among them (``livedrummer acoustic train``'s default ``--hold-out``), so a
TimGM6mb render is a kit it never heard; the floors below sit at or under what this clip
measures. The model is a mix's default recogniser; it does not yet meet issue 30's goals (see
docs/acoustic.md). Training on a tiny corpus (the built-in synth, one short excerpt, two
epochs) is run twice with separate caches and must give the same file.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from livedrummer.acoustic.augment import apply, condition
from livedrummer.acoustic.detector import HIT_DTYPE, OnlineDetector, detect, tail_samples
from livedrummer.acoustic.model import ModelError, load_model, read_model
from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.profile import load_profile
from livedrummer.acoustic.score import score
from livedrummer.acoustic.train import label_candidates
from services.bench._drumaudio import DEFAULT_SF2, SR, excerpt, render_mix
from services.bench._kitcorpus import GROUPS_MIX

REPO = Path(__file__).resolve().parents[3]
HELD_OUT = "drummer1/eval_session/7_pop-groove7_138_beat_4-4.mid"  # split "test" in info.csv


@pytest.fixture(scope="module")
def unheard(groove_dir: Path):  # type: ignore[no-untyped-def]
    if not DEFAULT_SF2.is_file():
        reason = f"{DEFAULT_SF2} missing (Debian: apt-get install timgm6mb-soundfont)"
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)
    ex = excerpt(groove_dir / HELD_OUT, 4.0, 8.0)
    return ex, render_mix(ex, DEFAULT_SF2, seed=5)


def test_the_shipped_model_transcribes_a_kit_it_was_not_trained_on(unheard) -> None:  # type: ignore[no-untyped-def]
    ex, mix = unheard
    model = load_model(None)
    assert "timgm6mb" not in model.name  # the test's kit never entered training
    hits = detect(mix, SR, load_profile(None), model=model)
    got = score(
        hits["time_s"],
        hits["cls"],
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        GROUPS_MIX,
    )
    # measured: kick 0.80 (12 of 14), snare 0.86 (9 of 9, 3 false), hi-hat 0.90
    assert got["kick"].f >= 0.80, got
    assert got["snare"].f >= 0.80, got
    assert got["hihat"].f >= 0.75, got


def test_the_online_twin_with_the_model_gives_the_offline_hits(unheard) -> None:  # type: ignore[no-untyped-def]
    _ex, mix = unheard
    model, profile = load_model(None), load_profile(None)
    clip = mix[: 4 * SR]
    offline = detect(clip, SR, profile, model=model)
    det = OnlineDetector(profile, SR, model=model)
    rng = np.random.default_rng(2)
    data = np.concatenate([clip, np.zeros(tail_samples(2), np.float32)])
    out, pos = [], 0
    while pos < len(data):
        n = int(rng.integers(1, 3000))
        out.append(det.process(data[pos : pos + n]))
        pos += n
    online = np.concatenate(out) if out else np.zeros(0, HIT_DTYPE)
    assert len(offline) > 10
    np.testing.assert_array_equal(online, offline)


def test_acoustic_train_is_deterministic(groove_dir: Path, tmp_path: Path) -> None:
    outs = []
    for run in ("a", "b"):
        env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / f"cache-{run}")}
        out = tmp_path / f"model-{run}.npz"
        r = subprocess.run(
            [
                sys.executable,
                "-m",
                "services",
                "acoustic",
                "train",
                "--kits",
                "builtin",
                "--hold-out",
                "none",
                "--files",
                "1",
                "--seconds",
                "3",
                "--epochs",
                "2",
                "--corpus",
                str(groove_dir),
                "-o",
                str(out),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=120,
            env=env,
        )
        assert r.returncode == 0, r.stderr
        assert "trained on builtin" in r.stdout
        outs.append(read_model(out))
    a, b = outs
    for key in ("mean", "std", "w1", "b1", "w2", "b2", "ref_level"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key))
    assert not np.allclose(a.w1, 0.0)


def test_acoustic_train_bad_options_are_one_line(tmp_path: Path) -> None:
    for argv, says in (
        (["--hold-out", "nokit"], "--hold-out: unknown kit 'nokit'"),
        (["--kits", "nokit"], "unknown kit 'nokit'"),
        (["--files", "0"], "must be positive"),
    ):
        r = subprocess.run(
            [
                sys.executable,
                "-m",
                "services",
                "acoustic",
                "train",
                *argv,
                "-o",
                str(tmp_path / "m.npz"),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert says in r.stderr


def test_a_wrong_model_file_is_named(tmp_path: Path) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_text("not numpy")
    with pytest.raises(ModelError, match=r"bad\.npz: not a model file"):
        read_model(bad)
    good = load_model(None)
    arrays = {k: getattr(good, k) for k in ("mean", "std", "w1", "b1", "w2", "b2")}
    np.savez(tmp_path / "short.npz", **arrays)
    with pytest.raises(ModelError, match=r"short\.npz: no array .ref_level."):
        read_model(tmp_path / "short.npz")
    with pytest.raises(ModelError, match=r"nothere\.npz: no such file"):
        load_model(tmp_path / "nothere.npz")


def test_labels_take_strokes_just_before_a_candidate_and_high_onsets_only_cymbals() -> None:
    kick, hat = CLASSES.index("kick"), CLASSES.index("hihat_closed")
    ref_t = np.array([1.000, 1.002, 2.000])
    ref_c = np.array([kick, hat, kick])
    times = np.array([1.010, 1.030, 1.995, 1.010])
    high = np.array([False, False, False, True])
    y = label_candidates(times, high, ref_t, ref_c)
    assert y[0, kick] == 1 and y[0, hat] == 1  # 10 and 8 ms before
    assert y[1].sum() == 0  # 30 ms after: a decay, not the stroke
    assert y[2, kick] == 1  # 5 ms after the candidate
    assert y[3, kick] == 0 and y[3, hat] == 1  # a high-band candidate is no kick


def test_conditions_are_seeded_and_the_room_rings() -> None:
    dry = np.zeros(SR)
    dry[1000] = 1.0
    c = condition(np.random.default_rng(3))
    a, b = apply(dry, c, SR, 9), apply(dry, c, SR, 9)
    np.testing.assert_array_equal(a, b)
    assert float(np.max(np.abs(a))) == pytest.approx(0.9, abs=1e-6)
    short = apply(dry, c.__class__(**{**c.__dict__, "rt60_s": 0.1, "noise_db": -120}), SR, 9)
    long = apply(dry, c.__class__(**{**c.__dict__, "rt60_s": 0.8, "noise_db": -120}), SR, 9)
    late = slice(1000 + int(0.2 * SR), 1000 + int(0.5 * SR))
    assert np.sum(long[late] ** 2) > 100 * np.sum(short[late] ** 2)
