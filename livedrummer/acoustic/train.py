"""Training the hit classifier (:mod:`.model`): labels from a MIDI ground truth, then a small MLP.

Training data are the onset *candidates* the detector finds in rendered audio (every onset
its picking takes at the model's thresholds, whatever it would be classified as), each with
its feature vector; a candidate's label for a class is 1 when a true stroke of that class lies
within :data:`LABEL_BEFORE_S` before to :data:`LABEL_AFTER_S` after it (the detector stamps an
onset a few ms either side of its attack; a stroke later than that is not yet in the frames the
decision sees and gets an onset of its own). Candidates with no stroke near are all-zero rows:
the model learns to reject a decay's bump, a ring's wobble and noise. A high-band candidate
can only be a hi-hat or cymbal (:data:`~.detector.HIGH_CLASSES`), so its other labels are 0.

**Per recording.** Candidates come grouped by take (one recording) in their order, because the
network's input holds the onset spectrum less the take's running mean (:class:`.model.
RecordingNorm`), computed here as the detector computes it (:func:`.model.running_means`).

**Augmentation in the feature domain** (:func:`coloured`, off by default): each take can be seen
``copies`` times (``acoustic train --copies``), the first as rendered, the others through a
fresh microphone EQ and gain (drawn as :func:`.augment.condition` draws one). A gain ``g`` per
band adds ``log10 g`` to every frame's log band and to the rise (the rise is a difference of two
frames through the same filter), and moves the running mean by the same offset times the share
of the mean that is not the prior; so a coloured copy is what the detector would have seen of
that recording through that EQ (a band that did not rise stays at the floor), up to the noise
floor's own level, at the cost of an addition instead of a render.

The fit is plain minibatch Adam on binary cross-entropy, in float32 (twice the speed of float64
on the shared CPUs this trains on; the model file is float32 anyway), with a cosine-decayed
step size and a seeded generator for
the initial weights, the augmentation and the batch order: the same corpus gives the same
weights, bit for bit, on one machine (BLAS may order sums differently elsewhere; the
differences are rounding).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from livedrummer.acoustic.augment import condition, eq_gain
from livedrummer.acoustic.model import (
    _FLOOR,
    HIDDEN,
    N_FEATURES,
    N_FRAMES,
    THRESHOLDS,
    HitModel,
    model_input,
    onset_spectrum,
    running_means,
)
from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.spectrum import CLASS_SIZE, N_BANDS, band_edges

LABEL_BEFORE_S = 0.020
LABEL_AFTER_S = 0.008
HIGH_CODES = [CLASSES.index(c) for c in ("hihat_closed", "hihat_open", "crash", "ride")]
#: Copies of each take in training: as rendered, then through fresh EQs and gains. 1 (none):
#: three copies cost the kick on kits it never heard (a TimGM6mb clip: kick F 0.21 with three,
#: 0.80 with one; the built-in synth's candidates: 0.17 and 0.30), the rendered takes' own
#: drawn EQs (:mod:`.augment`) are colouring enough.
COPIES = 1
GAIN_DB = 12.0  # the coloured copies' gain: within +-GAIN_DB
_SR = 48_000
_LOG_FLOOR = float(np.log10(_FLOOR))


@dataclass(frozen=True)
class TakeCandidates:
    """One recording's candidates, in order: features (n, N_FEATURES), labels (n, classes),
    band-rise totals (n,)."""

    features: np.ndarray
    labels: np.ndarray
    levels: np.ndarray


def label_candidates(
    times: np.ndarray, high: np.ndarray, ref_times: np.ndarray, ref_classes: np.ndarray
) -> np.ndarray:
    """(n, len(CLASSES)) 0/1 labels of candidates at ``times`` (see the module docstring)."""
    out = np.zeros((len(times), len(CLASSES)))
    for code in range(len(CLASSES)):
        ref = np.sort(ref_times[ref_classes == code])
        if not len(ref):
            continue
        lo = np.searchsorted(ref, times - LABEL_BEFORE_S, side="left")
        hi = np.searchsorted(ref, times + LABEL_AFTER_S, side="right")
        out[:, code] = hi > lo
    mask = np.zeros(len(CLASSES), bool)
    mask[HIGH_CODES] = True
    out[np.asarray(high, bool)[:, None] & ~mask[None, :]] = 0.0
    return out


def band_centres_hz() -> np.ndarray:
    """The classification bands' centre frequencies (geometric) at 48 kHz."""
    edges = band_edges(_SR).astype(np.float64) * _SR / CLASS_SIZE
    out: np.ndarray = np.sqrt(edges[:-1] * edges[1:])
    return out


def coloured(features: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``features`` (n, N_FEATURES) of a recording heard with ``offset`` (N_BANDS,) added to
    every log band (a gain per band, log10; see the module docstring)."""
    top = features[:, -2:-1]
    n = N_FRAMES * N_BANDS
    logs = features[:, :n].reshape(-1, N_FRAMES, N_BANDS) + top[:, :, None] + offset
    rise = features[:, n : n + N_BANDS] + top
    silent = rise <= _LOG_FLOOR + 1e-9  # no rise: stays at the floor whatever the gain
    rise = np.where(silent, _LOG_FLOOR, rise + offset)
    new_top = logs[:, -1].max(axis=1, keepdims=True)
    rel = (logs - new_top[:, :, None]).reshape(len(features), n)
    return np.concatenate([rel, rise - new_top, new_top, features[:, -1:]], axis=1)


def training_set(
    takes: Sequence[TakeCandidates], seed: int = 0, copies: int = COPIES
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Network inputs, labels and levels of every take's copies (see the module docstring),
    and the prior (the corpus's mean onset spectrum) they were normalised with."""
    rng = np.random.default_rng([seed, 1])
    every = np.concatenate([t.features for t in takes if len(t.features)])
    prior = onset_spectrum(every).mean(axis=0)
    centres = band_centres_hz()
    xs, ys, ls = [], [], []
    for take in takes:
        if not len(take.features):
            continue
        means, share = running_means(take.features, prior)
        for copy in range(copies):
            offset = np.zeros(N_BANDS)
            if copy:
                gain_db = rng.uniform(-GAIN_DB, GAIN_DB)
                offset = np.log10(eq_gain(condition(rng), centres)) + gain_db / 20
            feats = coloured(take.features, offset) if copy else take.features
            xs.append(model_input(feats, means + (1.0 - share)[:, None] * offset))
            ys.append(take.labels)
            ls.append(take.levels * 10 ** (offset.mean()))
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(ls), prior


def fit(
    takes: Sequence[TakeCandidates],
    seed: int = 0,
    epochs: int = 8,
    batch: int = 512,
    lr: float = 2e-3,
    weight_decay: float = 1e-4,
    name: str = "model",
    hidden: tuple[int, int] = HIDDEN,
    copies: int = COPIES,
) -> HitModel:
    """A model fitted to the candidates of ``takes`` (each in its recording's order)."""
    for t in takes:
        if t.features.shape[1:] != (N_FEATURES,) or len(t.features) != len(t.labels):
            raise ValueError(f"features {t.features.shape} and labels {t.labels.shape} do not fit")
    inputs, labels, levels, prior = training_set(takes, seed, copies)
    rng = np.random.default_rng(seed)
    mean = inputs.mean(axis=0)
    std = inputs.std(axis=0) + 1e-3
    x_all = ((inputs - mean) / std).astype(np.float32)
    labels = labels.astype(np.float32)
    k = labels.shape[1]
    sizes = (x_all.shape[1], *hidden, k)
    params: list[np.ndarray] = []
    for i, (a, b) in enumerate(itertools.pairwise(sizes)):
        last = i == len(sizes) - 2
        w = rng.standard_normal((a, b)) * np.sqrt((1.0 if last else 2.0) / a)
        params.append(w.astype(np.float32))
        params.append(np.full(b, -2.0 if last else 0.0, np.float32))
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    b1, b2, eps = np.float32(0.9), np.float32(0.999), 1e-8
    step = 0
    n = len(x_all)
    total = epochs * ((n + batch - 1) // batch)
    for _epoch in range(epochs):
        order = rng.permutation(n)
        for start in range(0, n, batch):
            idx = order[start : start + batch]
            x, y = x_all[idx], labels[idx]
            w1, c1, w2, c2, w3, c3 = params
            pre1 = x @ w1 + c1
            h1 = np.maximum(pre1, 0.0)
            pre2 = h1 @ w2 + c2
            h2 = np.maximum(pre2, 0.0)
            z = h2 @ w3 + c3
            prob = 1.0 / (1.0 + np.exp(-np.clip(z, -40, 40)))
            dz = (prob - y) / len(idx)
            dh2 = (dz @ w3.T) * (pre2 > 0)
            dh1 = (dh2 @ w2.T) * (pre1 > 0)
            grads = [x.T @ dh1 + weight_decay * w1, dh1.sum(axis=0),
                     h1.T @ dh2 + weight_decay * w2, dh2.sum(axis=0),
                     h2.T @ dz + weight_decay * w3, dz.sum(axis=0)]  # fmt: skip
            step += 1
            rate = np.float32(lr * 0.5 * (1 + np.cos(np.pi * step / total)))  # cosine decay
            for i, g in enumerate(grads):
                m[i] = b1 * m[i] + (1 - b1) * g
                v[i] = b2 * v[i] + (1 - b2) * g * g
                mh = m[i] / np.float32(1 - b1**step)
                vh = v[i] / np.float32(1 - b2**step)
                params[i] = params[i] - rate * mh / (np.sqrt(vh) + np.float32(eps))
    ref = np.ones(k)
    for c in range(k):
        mine = levels[labels[:, c] > 0]
        if len(mine):
            ref[c] = float(np.percentile(mine, 95))
    w1, c1, w2, c2, w3, c3 = (p.astype(np.float64) for p in params)
    thresholds = np.array(THRESHOLDS, np.float64)
    return HitModel(mean, std, w1, c1, w2, c2, w3, c3, prior, ref, thresholds, name=name)
