"""Templates and level calibration from hits of known drums (``audio learn``, ``audio profile``).

A drum's templates are the band rises (:mod:`.detector`'s classification feature) of its hits,
each normalised to sum 1, averaged within three loudness groups (soft, middle, loud: a drum's
spectrum brightens as it is struck harder, so one average would fit neither end); its level is
the median rise of its loudest third, taken as a full-strength (velocity 127) hit. Onsets
under :data:`WOBBLE` of the drum's loudest are left out (a ringing cymbal's decay). Hits are
found by the same onset picking as the detector's, so a template is exactly the feature the
detector will see; the picking settings used are the profile's own (``lookahead`` too: a
profile that decides sooner reads its templates sooner). A way of striking a drum that sounds
like none of its other strokes (a SoundFont's side stick, its ride bell) gets a template of
its own, outside the loudness groups, and leaves the level alone. :data:`OTHER_STROKES` names
them once, for both: ``audio profile`` renders their General MIDI notes, ``audio learn`` asks
the drummer for them (each ~8 hits, right after the plain strokes of their drum) with a
prompt that says how to play them, and leaves out their onsets under :data:`WOBBLE` of their
loudest as it does a drum's (:func:`real_hits`: a bell rings on as a bow does; ``audio
profile`` keeps all of a note's onsets, as its shipped profiles were made).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from livedrummer.acoustic.detector import OnlineDetector, tail_samples
from livedrummer.acoustic.pieces import CLASSES
from livedrummer.acoustic.profile import AudioProfile, DetectorSettings
from livedrummer.acoustic.spectrum import N_BANDS
from livedrummer.errors import LivedrummerError

GROUPS = 3
#: A rise under this share of a drum's loudest is its ring wobbling, not a hit: a cymbal's
#: decay makes small onsets (up to 40 of them after six crash hits of a SoundFont).
WOBBLE = 0.1


class LearnError(LivedrummerError):
    """Too few hits were heard to learn a drum."""


@dataclass(frozen=True)
class OtherStroke:
    """A way of striking a drum that sounds like none of its plain strokes."""

    drum: str  #: the class it is a stroke of (:data:`~.pieces.CLASSES`)
    note: int  #: its General MIDI note (what ``audio profile`` renders)
    prompt: str  #: what ``audio learn`` asks the drummer to play


#: The other strokes by the name ``audio learn --other-strokes`` takes (each asked for right
#: after its drum's plain strokes).
OTHER_STROKES = {
    "side-stick": OtherStroke(
        "snare", 37, "side stick: lay the stick on the snare and click the rim"
    ),
    "ride-bell": OtherStroke(
        "ride",
        53,
        "ride bell: strike the bell (the ride's raised centre) with the stick's shoulder",
    ),
}


def parse_other_strokes(spec: str, where: str = "--other-strokes") -> list[str]:
    """``side-stick,ride-bell`` (or ``none``) → names of :data:`OTHER_STROKES`, in its order."""
    names = [n.strip().lower() for n in spec.split(",") if n.strip()]
    if names == ["none"]:
        return []
    if bad := [n for n in names if n not in OTHER_STROKES]:
        raise LivedrummerError(
            f"{where}: unknown stroke {bad[0]!r} (one of {', '.join(OTHER_STROKES)}, or none)"
        )
    return [n for n in OTHER_STROKES if n in names]


def real_hits(rises: np.ndarray) -> np.ndarray:
    """``rises`` (hits, N_BANDS) without the empty ones and those under :data:`WOBBLE` of the
    loudest (a ringing drum's decay, not a hit)."""
    sums = rises.sum(axis=1)
    if not len(sums):
        return rises
    kept: np.ndarray = rises[(sums >= WOBBLE * sums.max()) & (sums > 0)]
    return kept


def hit_rises(audio: np.ndarray, sr: int, settings: DetectorSettings | None = None) -> np.ndarray:
    """The band rise (hits, N_BANDS) of every onset in mono ``audio``."""
    collector = HitCollector(sr, settings)
    rises = collector.process(
        np.concatenate([np.asarray(audio, np.float64), np.zeros(tail_samples())])
    )
    return np.array(rises).reshape(-1, N_BANDS)


def build_profile(
    name: str,
    rises: Mapping[int, np.ndarray],
    settings: DetectorSettings | None = None,
    min_hits: int = 3,
    other_sounds: Mapping[int, Sequence[np.ndarray]] | None = None,
) -> AudioProfile:
    """A profile from each class's hit rises (class code → (hits, N_BANDS)).

    ``other_sounds``: more ways a class sounds (class code → rises of each, e.g. a snare's
    side stick), one template each (their mean shape), the class's level untouched: a side
    stick is a snare stroke whose click is nothing like the head's sound, so the head's
    loudness groups cannot hold it."""
    templates: list[np.ndarray] = []
    owners: list[int] = []
    levels = np.zeros(len(CLASSES))
    for code, r in sorted(rises.items()):
        r = real_hits(r)
        sums = r.sum(axis=1)
        if len(r) < min_hits:
            raise LearnError(f"{CLASSES[code]}: heard {len(r)} hits, need at least {min_hits}")
        order = np.argsort(sums)
        for group in np.array_split(order, min(GROUPS, len(order))):
            shape = (r[group] / sums[group, None]).mean(axis=0)
            templates.append(shape / shape.sum())
            owners.append(code)
        loud = sums[order[-max(1, len(order) // 3) :]]
        levels[code] = float(np.median(loud))
        for other in (other_sounds or {}).get(code, ()):
            other = other[other.sum(axis=1) > 0]
            if len(other):
                shape = (other / other.sum(axis=1, keepdims=True)).mean(axis=0)
                templates.append(shape / shape.sum())
                owners.append(code)
    return AudioProfile(
        name,
        np.array(templates),
        np.array(owners, np.int64),
        levels,
        settings or DetectorSettings(),
    )


#: Velocities each note of a SoundFont is struck at to make its profile (loud to soft).
SOUNDFONT_VELOCITIES = (127, 112, 96, 80, 64, 48)
SOUNDFONT_SPACING_S = 0.6
_SKIP_NOTES = frozenset({39})  # hand clap: no drum of the kit
#: Notes whose class sounds unlike its other notes: templates of their own (the side stick's
#: click is a snare stroke, the ride's bell a ride stroke).
_OWN_SOUND_NOTES = frozenset(s.note for s in OTHER_STROKES.values())


def soundfont_profile(
    sf2: object, sr: int, name: str = "general-midi", settings: DetectorSettings | None = None
) -> AudioProfile:
    """A profile from isolated hits of every General MIDI drum note of a SoundFont (each
    class's notes, at :data:`SOUNDFONT_VELOCITIES`), rendered by FluidSynth; its hits picked
    and its templates read with ``settings`` (e.g. another ``lookahead``), which it keeps."""
    from pathlib import Path

    from livedrummer.acoustic.pieces import class_of
    from livedrummer.audio.soundfont import render_soundfont
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.events import ONSET_DTYPE

    gm = load_note_map("general-midi")
    rises: dict[int, list[np.ndarray]] = {}
    own: dict[int, list[np.ndarray]] = {}
    for note, spec in sorted(gm.notes.items()):
        code = class_of(spec.instrument, spec.zone, spec.hihat)
        if code < 0 or note in _SKIP_NOTES:
            continue
        hits = np.zeros(len(SOUNDFONT_VELOCITIES), ONSET_DTYPE)
        hits["time_s"] = 0.2 + SOUNDFONT_SPACING_S * np.arange(len(hits))
        hits["note"], hits["velocity"] = note, SOUNDFONT_VELOCITIES
        hits["channel"], hits["instrument"] = 9, spec.instrument_code
        hits["zone"], hits["hihat"] = spec.zone.code, spec.hihat.code
        duration = float(hits["time_s"][-1]) + SOUNDFONT_SPACING_S
        audio = render_soundfont(hits, duration, Path(str(sf2)), sr).mean(axis=1)
        found = hit_rises(audio, sr, settings)
        if note in _OWN_SOUND_NOTES:
            own.setdefault(code, []).append(found)
        else:
            rises.setdefault(code, []).extend(found)
    return build_profile(
        name, {c: np.array(r) for c, r in rises.items()}, settings, other_sounds=own
    )


class HitCollector:
    """Online: the band rise of every onset in a stream (what ``audio learn`` listens with).

    ``process(block)`` (mono float samples) returns the rises of the onsets decided in it;
    :meth:`reset` starts over. The same picking as the detector's, so each rise is the feature
    the detector will see for that hit.
    """

    def __init__(self, sr: int, settings: DetectorSettings | None = None) -> None:
        flat = AudioProfile(
            "learn",
            np.full((1, N_BANDS), 1.0 / N_BANDS),
            np.zeros(1, np.int64),
            np.zeros(len(CLASSES)),
            settings or DetectorSettings(),
        )
        self._det = OnlineDetector(flat, sr, one_drum=True)
        self.reset()

    def reset(self) -> None:
        self._det.reset()
        self._features: list[np.ndarray] = []
        self._det.features = self._features

    def process(self, block: np.ndarray) -> list[np.ndarray]:
        before = len(self._features)
        self._det.process(block)
        return self._features[before:]
