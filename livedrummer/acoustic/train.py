"""Training the hit classifier (:mod:`.model`): labels from a MIDI ground truth, then a small MLP.

Training data are the onset *candidates* the detector finds in rendered audio (every onset
its picking takes at the model's thresholds, whatever it would be classified as), each with
its feature vector; a candidate's label for a class is 1 when a true stroke of that class lies
within :data:`LABEL_BEFORE_S` before to :data:`LABEL_AFTER_S` after it (the detector stamps an
onset a few ms either side of its attack; a stroke later than that is not yet in the frames the
decision sees and gets an onset of its own). Candidates with no stroke near are all-zero rows:
the model learns to reject a decay's bump, a ring's wobble and noise. A high-band candidate
can only be a hi-hat or cymbal (:data:`~.detector.HIGH_CLASSES`), so its other labels are 0.

The fit is plain minibatch Adam on binary cross-entropy, float64, with a seeded generator for
the initial weights and the batch order: the same corpus gives the same weights, bit for bit,
on one machine (BLAS may order sums differently elsewhere; the differences are rounding).
"""

from __future__ import annotations

import numpy as np

from livedrummer.acoustic.model import HIDDEN, N_FEATURES, HitModel
from livedrummer.acoustic.pieces import CLASSES

LABEL_BEFORE_S = 0.020
LABEL_AFTER_S = 0.008
HIGH_CODES = [CLASSES.index(c) for c in ("hihat_closed", "hihat_open", "crash", "ride")]


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


def fit(
    features: np.ndarray,
    labels: np.ndarray,
    levels: np.ndarray,
    seed: int = 0,
    epochs: int = 12,
    batch: int = 512,
    lr: float = 2e-3,
    weight_decay: float = 1e-4,
    name: str = "model",
    hidden: int = HIDDEN,
) -> HitModel:
    """A model fitted to ``features`` (n, N_FEATURES) and ``labels`` (n, classes);
    ``levels`` (n,) are the candidates' band-rise totals (for the velocity reference)."""
    if features.shape[1] != N_FEATURES or len(features) != len(labels):
        raise ValueError(f"features {features.shape} and labels {labels.shape} do not fit")
    rng = np.random.default_rng(seed)
    mean = features.mean(axis=0)
    std = features.std(axis=0) + 1e-3
    x_all = (features - mean) / std
    k = labels.shape[1]
    params = [
        rng.standard_normal((N_FEATURES, hidden)) * np.sqrt(2.0 / N_FEATURES),
        np.zeros(hidden),
        rng.standard_normal((hidden, k)) * np.sqrt(1.0 / hidden),
        np.full(k, -2.0),
    ]
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    b1, b2, eps = 0.9, 0.999, 1e-8
    step = 0
    n = len(x_all)
    for _epoch in range(epochs):
        order = rng.permutation(n)
        for start in range(0, n, batch):
            idx = order[start : start + batch]
            x, y = x_all[idx], labels[idx]
            w1, c1, w2, c2 = params
            pre = x @ w1 + c1
            h = np.maximum(pre, 0.0)
            z = h @ w2 + c2
            prob = 1.0 / (1.0 + np.exp(-np.clip(z, -40, 40)))
            dz = (prob - y) / len(idx)
            dh = (dz @ w2.T) * (pre > 0)
            grads = [x.T @ dh + weight_decay * w1, dh.sum(axis=0), h.T @ dz + weight_decay * w2,
                     dz.sum(axis=0)]  # fmt: skip
            step += 1
            for i, g in enumerate(grads):
                m[i] = b1 * m[i] + (1 - b1) * g
                v[i] = b2 * v[i] + (1 - b2) * g * g
                mh = m[i] / (1 - b1**step)
                vh = v[i] / (1 - b2**step)
                params[i] = params[i] - lr * mh / (np.sqrt(vh) + eps)
    ref = np.ones(k)
    for c in range(k):
        mine = levels[labels[:, c] > 0]
        if len(mine):
            ref[c] = float(np.percentile(mine, 95))
    return HitModel(mean, std, params[0], params[1], params[2], params[3], ref, name=name)
