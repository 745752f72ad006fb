"""A learned hit classifier: which drums an onset holds, from the spectra the detector already has.

Why a learned classifier and not templates: a template is one kit's sound. Fixed-basis NMF with
the ``general-midi`` templates found 0 of 20 snares of a sampled acoustic kit (issue 30): the
snare's band shape differs more between kits than between a snare and a tom of one kit. A small
network trained on many kits, rooms, microphone colourings and noise floors learns what stays
the same across them (a snare's broad noise above a tone, a kick's low thump, a hat's energy
above 6 kHz with little below). The onset picking is unchanged (:mod:`.detector`'s SuperFlux and
high-band functions, here at the model's own lower thresholds: a missed onset cannot be
recovered, a false one is the classifier's to reject), so the twins, the latency and the cost
per frame stay; the network runs once per onset (a 170 x 48 and a 48 x 9 product, some 20
microseconds).

**Features** (:func:`hit_features`): the five 21 ms band spectra the detector keeps for an
onset at frame ``p`` (frames ``p - 2`` to ``p + lookahead``, so nothing the decision does not
already wait for), as log10 magnitudes relative to the newest frame's loudest band, plus the
log rise (newest minus oldest, clipped at zero) on the same scale, the loudness itself and
whether the high-band onset function found the onset. Relative logs make the feature blind to
the track's gain; the loudness is there for velocity-dependent timbre.

**Network**: one hidden layer of :data:`HIDDEN` ReLU units, one sigmoid output per class
(several drums can sound in one onset), standardised inputs. A class is reported when its
probability reaches :attr:`HitModel.threshold`. Velocity: ``127 * sqrt(rise / ref)`` with ``ref``
the class's loud-hit rise in the training corpus (what the template path does with its
levels). Limits: trained on rendered kits (SoundFonts, Hydrogen kits, the built-in synth) with
synthetic rooms, not on recordings; three toms are told apart by pitch only as well as kits
agree on it; the lookahead is fixed by the model (it was trained on five frames).

The model file is an ``.npz`` of the arrays below (``kits/audio/acoustic-model.npz`` is the
bundled one, made by ``livedrummer acoustic train``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.spectrum import N_BANDS
from livedrummer.errors import ConfigError
from livedrummer.resources import search_dirs

HIDDEN = 48
N_FRAMES = 5  # BEFORE (2) + the onset frame + lookahead (2)
N_FEATURES = N_FRAMES * N_BANDS + N_BANDS + 2
LOOKAHEAD = 2
_FLOOR = 1e-7
BUNDLED = "acoustic-model"
#: Onset picking thresholds (``delta``, ``floor`` of :class:`~.profile.DetectorSettings`) the
#: model's candidates are picked at, in training and, unless its file says otherwise, in use.
PICK_DELTA = 1.0
PICK_FLOOR = 1.5


class ModelError(ConfigError):
    """A model file is missing or wrong."""


def hit_features(frames: np.ndarray, high: bool) -> np.ndarray:
    """The feature vector (:data:`N_FEATURES`) of an onset from its band spectra
    ``frames`` (:data:`N_FRAMES`, N_BANDS), oldest first."""
    logs = np.log10(_FLOOR + frames)
    top = float(logs[-1].max())
    rise = np.log10(_FLOOR + np.maximum(frames[-1] - frames[0], 0.0))
    return np.concatenate([(logs - top).ravel(), rise - top, [top, 1.0 if high else 0.0]])


@dataclass(frozen=True)
class HitModel:
    """Weights and what inference needs around them (see the module docstring)."""

    mean: np.ndarray  # (N_FEATURES,)
    std: np.ndarray
    w1: np.ndarray  # (N_FEATURES, HIDDEN)
    b1: np.ndarray
    w2: np.ndarray  # (HIDDEN, len(CLASSES))
    b2: np.ndarray
    ref_level: np.ndarray  # (len(CLASSES),): a loud hit's band rise
    threshold: float = 0.5
    delta: float = PICK_DELTA  # onset picking thresholds used with this model
    floor: float = PICK_FLOOR
    name: str = "model"

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        """(len(CLASSES),) or (n, len(CLASSES)) probabilities of each class sounding."""
        x = (features - self.mean) / self.std
        h = np.maximum(x @ self.w1 + self.b1, 0.0)
        z = h @ self.w2 + self.b2
        out: np.ndarray = 1.0 / (1.0 + np.exp(-np.clip(z, -40, 40)))
        return out

    def save(self, path: Path) -> None:
        np.savez_compressed(
            path, mean=self.mean, std=self.std, w1=self.w1, b1=self.b1, w2=self.w2, b2=self.b2,
            ref_level=self.ref_level,
            scalars=np.array([self.threshold, self.delta, self.floor]),
            name=np.array(self.name), classes=np.array(CLASSES),
        )  # fmt: skip


_SHAPES = {
    "mean": (N_FEATURES,), "std": (N_FEATURES,), "w1": (N_FEATURES, HIDDEN), "b1": (HIDDEN,),
    "w2": (HIDDEN, len(CLASSES)), "b2": (len(CLASSES),), "ref_level": (len(CLASSES),),
    "scalars": (3,),
}  # fmt: skip


def read_model(path: Path) -> HitModel:
    """A model from its ``.npz`` (a :class:`ModelError` naming the file and array if wrong)."""
    try:
        data = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as e:
        raise ModelError(f"{path}: not a model file ({e})") from None
    with data:
        arrays = {}
        for key, shape in _SHAPES.items():
            if key not in data.files:
                raise ModelError(f"{path}: no array {key!r}")
            a = np.asarray(data[key], np.float64)
            if a.shape != shape or not np.all(np.isfinite(a)):
                raise ModelError(f"{path}: {key}: expected {shape} finite numbers, got {a.shape}")
            arrays[key] = a
        if "classes" in data.files and tuple(str(c) for c in data["classes"]) != CLASSES:
            raise ModelError(f"{path}: classes {list(data['classes'])} are not {list(CLASSES)}")
        name = str(data["name"]) if "name" in data.files else path.stem
    if np.any(arrays["std"] <= 0):
        raise ModelError(f"{path}: std: every value must be positive")
    threshold, delta, floor = (float(v) for v in arrays.pop("scalars"))
    return HitModel(**arrays, threshold=threshold, delta=delta, floor=floor, name=name)


def load_model(spec: str | Path | None = None) -> HitModel:
    """A model by path (``*.npz``), or by name in the ``kits/audio`` search folders (the
    bundled :data:`BUNDLED` for ``None``)."""
    spec = BUNDLED if spec is None else spec
    path = Path(spec)
    if path.suffix != ".npz":
        hits = [d / f"{spec}.npz" for d in search_dirs("kits/audio")]
        found = [p for p in hits if p.is_file()]
        if not found:
            raise ModelError(f"acoustic model {spec!r} not found in kits/audio")
        path = found[-1]
    elif not path.is_file():
        raise ModelError(f"{path}: no such file")
    return read_model(path)
