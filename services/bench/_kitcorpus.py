"""A multi-kit corpus: GMD grooves through every kit of :mod:`._kits`, each in its own conditions.

For ``livedrummer acoustic train`` and ``bench transcribe --leave-one-kit-out``. A *take* is a
groove excerpt played by one kit and put through one draw of recording conditions
(:func:`livedrummer.acoustic.augment.condition`: room, EQ, compression, noise; seeded by the
take's kit, split and number, so the same take is the same audio on every run). All takes of
one kit are rendered as one track (excerpts laid end to end, :data:`GAP_S` apart) and cut
apart again, because opening a SoundFont can take longer than playing it (MuseScore's
compressed ``.sf3``: 13 s to load, 0.5 s to play 10 s).

Training data for the model are the detector's candidates (:mod:`livedrummer.acoustic.train`)
of each take; :func:`kit_candidates` caches them per kit and corpus settings in
``$XDG_CACHE_HOME/livedrummer/acoustic`` (``~/.cache``), so a leave-one-kit-out run renders
each kit once and trains one model per held-out kit in seconds. Excerpts come from GMD's
train split for training and its test split for testing: every test figure is on grooves and
on a kit that training never heard.
"""

from __future__ import annotations

import os
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._kits import KitSource, renderer

if TYPE_CHECKING:
    from livedrummer.acoustic.train import TakeCandidates
import csv
from typing import TYPE_CHECKING

SR = 48_000
GAP_S = 3.0
#: Bump when rendering, conditions or features change: old cached candidates are then unused.
CORPUS_VERSION = 3
LEAK_DB = -20.0


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "livedrummer" / "acoustic"


@dataclass(frozen=True)
class Take:
    """One excerpt played by one kit: mono float32 audio and its ground truth."""

    kit: str
    name: str
    audio: np.ndarray
    ref_times: np.ndarray
    ref_classes: np.ndarray
    ref_velocities: np.ndarray


def _seed(*parts: object) -> int:
    return zlib.crc32("/".join(str(p) for p in parts).encode())


def excerpts(root: Path, split: str, count: int, seconds: float) -> list[object]:
    from ._drumaudio import excerpt

    return [excerpt(p, 5.0, seconds) for p in pick_files(root, split, count, seed=7)]


def _laid_out(
    exs: list,  # type: ignore[type-arg]
    classes: tuple[int, ...] | None = None,
) -> tuple[np.ndarray, list[int], float]:
    """Every excerpt's onsets on one time line (only ``classes``' strokes when given), each
    excerpt's first sample, the length."""
    parts, starts, t = [], [], 0.0
    for ex in exs:
        on = ex.onsets.copy()
        if classes is not None:
            on = on[np.isin(ex.classes, classes)]
        on["time_s"] += t
        parts.append(on)
        starts.append(round(t * SR))
        t += ex.duration_s + GAP_S
    return np.concatenate(parts), starts, t


def render_takes(kit: KitSource, exs: list, split: str) -> list[Take]:  # type: ignore[type-arg]
    """Each excerpt played by ``kit`` in its own conditions (see the module docstring)."""
    from livedrummer.acoustic.augment import apply, condition

    play = renderer(kit, cache_dir() / "sfz")
    onsets, starts, total = _laid_out(exs)
    track = play(onsets, total, SR)
    out = []
    for i, (ex, start) in enumerate(zip(exs, starts, strict=True)):
        dry = track[start : start + round(ex.duration_s * SR)]
        seed = _seed(kit.name, split, i)
        audio = apply(dry, condition(np.random.default_rng(seed)), SR, seed)
        ref = ex.onsets
        out.append(Take(kit.name, ex.name, audio, ref["time_s"], ex.classes, ref["velocity"]))
    return out


def render_stem_takes(kit: KitSource, exs: list, split: str) -> list[tuple[np.ndarray, list[str]]]:  # type: ignore[type-arg]
    """One microphone per drum of each excerpt: (n, mics) float32 with crosstalk
    (:data:`LEAK_DB`, 1 ms late), the same conditions on every microphone, and the mics'
    names (keys of :data:`._drumaudio.MICS`)."""
    from livedrummer.acoustic.augment import apply, condition
    from livedrummer.acoustic.pieces import CLASSES

    from ._drumaudio import MICS

    play = renderer(kit, cache_dir() / "sfz")
    tracks = {}
    for mic, classes in MICS.items():
        codes = tuple(CLASSES.index(c) for c in classes)
        onsets, starts, total = _laid_out(exs, codes)
        if len(onsets):
            tracks[mic] = play(onsets, total, SR)
    out = []
    for i, (ex, start) in enumerate(zip(exs, starts, strict=True)):
        n = round(ex.duration_s * SR)
        names = [
            m
            for m, cl in MICS.items()
            if m in tracks and np.isin(ex.classes, [CLASSES.index(c) for c in cl]).any()
        ]
        stems = np.stack([tracks[m][start : start + n] for m in names], axis=1)
        delay = int(0.001 * SR)
        late = np.zeros_like(stems)
        late[delay:] = stems[:-delay]
        mics = stems + 10 ** (LEAK_DB / 20) * (late.sum(axis=1, keepdims=True) - late)
        seed = _seed(kit.name, split, "stems", i)
        c = condition(np.random.default_rng(seed))
        out.append((apply(mics, c, SR, seed), names))
    return out


def take_candidates(take: Take) -> TakeCandidates:
    """The detector's candidates of one take, in order: features, labels, band-rise totals."""
    from livedrummer.acoustic.detector import OnlineDetector, tail_samples
    from livedrummer.acoustic.model import LOOKAHEAD, N_FEATURES
    from livedrummer.acoustic.pieces import CLASSES
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.train import TakeCandidates, label_candidates

    profile = load_profile(None)
    det = OnlineDetector(profile, SR)
    det.candidates = []
    audio = np.concatenate([take.audio, np.zeros(tail_samples(LOOKAHEAD), np.float32)])
    det.process(audio)
    if not det.candidates:
        return TakeCandidates(np.zeros((0, N_FEATURES)), np.zeros((0, len(CLASSES))), np.zeros(0))
    times = np.array([c[0] for c in det.candidates])
    feats = np.stack([c[1] for c in det.candidates])
    levels = np.array([c[2] for c in det.candidates])
    labels = label_candidates(times, feats[:, -1] > 0.5, take.ref_times, take.ref_classes)
    return TakeCandidates(feats, labels, levels)


def kit_candidates(kit: KitSource, root: Path, count: int, seconds: float) -> list[TakeCandidates]:
    """Candidates of ``count`` train-split takes of ``kit``, one entry per take (cached, see
    the module docstring)."""
    from livedrummer.acoustic.train import TakeCandidates

    path = cache_dir() / f"{kit.name}-train-{count}-{seconds:g}-v{CORPUS_VERSION}.npz"
    if path.is_file():
        with np.load(path) as data:
            x, y, level, take = data["x"], data["y"], data["level"], data["take"]
        return [
            TakeCandidates(x[take == i], y[take == i], level[take == i])
            for i in range(int(take.max()) + 1 if len(take) else 0)
        ]
    parts = [
        take_candidates(t)
        for t in render_takes(kit, excerpts(root, "train", count, seconds), "train")
    ]
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    take = np.concatenate([np.full(len(p.features), i) for i, p in enumerate(parts)])
    np.savez(
        tmp,
        x=np.concatenate([p.features for p in parts]),
        y=np.concatenate([p.labels for p in parts]),
        level=np.concatenate([p.levels for p in parts]),
        take=take,
    )
    tmp.replace(path)
    return parts


GROUPS_MIX = {
    "kick": ("kick",),
    "snare": ("snare",),
    "hihat": ("hihat_closed", "hihat_open"),
    "toms": ("tom_high", "tom_mid", "tom_low"),
    "cymbals": ("crash", "ride"),
}


def pick_files(root: Path, split: str, count: int | None, seed: int = 1) -> list[Path]:
    """``count`` beat (not fill) performances of ``split`` longer than 25 s, seeded choice
    (``None``: all of them)."""
    with (root / "info.csv").open() as f:
        rows = [
            r
            for r in csv.DictReader(f)
            if r["split"] == split and r["beat_type"] == "beat" and float(r["duration"]) > 25
        ]
    if count is None:
        return [root / r["midi_filename"] for r in rows]
    rng = np.random.default_rng(seed)
    chosen = rng.choice(len(rows), min(count, len(rows)), replace=False)
    return [root / rows[i]["midi_filename"] for i in sorted(chosen.tolist())]
