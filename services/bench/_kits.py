"""The drum kits the recogniser is trained and tested on: what is on this machine, rendered one way.

A kit is a name and a way to play an onset array: a General MIDI SoundFont (FluidSynth, as
:mod:`livedrummer.audio.soundfont`), an SFZ kit (:mod:`livedrummer.audio.sfz_render`), a
Hydrogen drumkit (its ``drumkit.xml`` turned into an SFZ file in a cache folder, see
:func:`hydrogen_sfz`) or the built-in synth (:mod:`livedrummer.audio.mix`). :data:`KITS` lists
the candidates by name with where Debian puts them (``deploy/system-deps.sh`` installs the
packages); :func:`available_kits` keeps those present and logs one line for each absent one.

Hydrogen's kits name their instruments freely ("BassDrum", "Pearl Tom Floor", "Sabian Hat
Closed"); :data:`ROLES` picks each General MIDI role's instrument by words in its name (the first
instrument that matches a role's words and none of its exclusions), and each role's sample
layers become regions on the role's GM notes with the layers' velocity ranges. A role the kit
lacks stays silent (its strokes are still in the ground truth: a kit without a ride cannot be
scored on the ride, and the table says so through its counts). Limits: Hydrogen's per-layer
pitch, ADSR and filter settings are not applied; stereo samples are played as their mean; a
layer whose sample file is absent is skipped with a log line.
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)

SF2 = Path("/usr/share/sounds/sf2")
SF3 = Path("/usr/share/sounds/sf3")
HYDROGEN = Path("/usr/share/hydrogen/data/drumkits")


@dataclass(frozen=True)
class KitSource:
    """A kit by name: ``kind`` (sf2, sfz, hydrogen, builtin), its file or folder, the Debian
    package that has it."""

    name: str
    kind: str
    path: Path | None
    package: str

    def present(self) -> bool:
        return self.path is None or self.path.exists()


KITS: tuple[KitSource, ...] = (
    KitSource("timgm6mb", "sf2", SF2 / "TimGM6mb.sf2", "timgm6mb-soundfont"),
    KitSource("fluidr3", "sf2", SF2 / "FluidR3_GM.sf2", "fluid-soundfont-gm"),
    KitSource(
        "musescore", "sf2", SF3 / "MuseScore_General_Lite.sf3", "musescore-general-soundfont-small"
    ),
    KitSource("builtin", "builtin", None, "(the built-in synth)"),
    KitSource("colombo", "hydrogen", HYDROGEN / "ColomboAcousticDrumkit", "hydrogen-drumkits"),
    KitSource("blackpearl", "hydrogen", HYDROGEN / "The Black Pearl 1.0", "hydrogen-drumkits"),
    KitSource("forzee", "hydrogen", HYDROGEN / "ForzeeStereo", "hydrogen-drumkits"),
    KitSource("millo", "hydrogen", HYDROGEN / "Millo_MultiLayered3", "hydrogen-drumkits"),
    KitSource("millo2", "hydrogen", HYDROGEN / "Millo_MultiLayered2", "hydrogen-drumkits"),
    KitSource("millo1", "hydrogen", HYDROGEN / "Millo-Drums_v.1", "hydrogen-drumkits"),
    KitSource("audiophob", "hydrogen", HYDROGEN / "Audiophob", "hydrogen-drumkits"),
    KitSource("varibreaks", "hydrogen", HYDROGEN / "VariBreaks", "hydrogen-drumkits"),
    KitSource("electricempire", "hydrogen", HYDROGEN / "ElectricEmpireKit", "hydrogen-drumkits"),
    KitSource("hardelectro", "hydrogen", HYDROGEN / "HardElectro1", "hydrogen-drumkits"),
    KitSource("bjapacific", "hydrogen", HYDROGEN / "BJA_Pacific", "hydrogen-drumkits"),
    KitSource("rumpf", "hydrogen", HYDROGEN / "rumpf_kit_z01_h2", "hydrogen-drumkits"),
)
KIT_NAMES = tuple(k.name for k in KITS)
#: The named held-out set: kits that never enter training of the bundled model nor the choice
#: of features, network or thresholds (the leave-one-kit-out rotation runs over the others).
#: Two sampled acoustic kits unlike the rest (BJA Pacific, rumpf) and TimGM6mb, the SoundFont
#: the template profile was made from (so the templates' row there is not held out).
HELD_OUT: tuple[str, ...] = ("timgm6mb", "bjapacific", "rumpf")


def available_kits(names: list[str] | None = None) -> list[KitSource]:
    """The kits of :data:`KITS` (or of ``names``) present here; one log line per absent one."""
    wanted = list(KIT_NAMES) if names is None else names
    out = []
    for name in wanted:
        kit = next((k for k in KITS if k.name == name), None)
        if kit is None:
            from livedrummer.errors import LivedrummerError

            raise LivedrummerError(f"unknown kit {name!r} (one of {', '.join(KIT_NAMES)})")
        if kit.present():
            out.append(kit)
        else:
            log.warning(
                "kit %s skipped: %s absent (Debian package %s)", name, kit.path, kit.package
            )
    return out


#: (GM notes it plays, words one of which its instrument name holds, words it must not hold)
ROLES: tuple[tuple[tuple[int, ...], tuple[str, ...], tuple[str, ...]], ...] = (
    ((35, 36), ("kick", "bassdrum", "bass drum"), ()),
    ((38, 40), ("snare",), ("rim", "roll", "stick", "jazz", "dry")),
    ((38, 40), ("snare",), ("rim", "roll", "stick")),
    ((37,), ("stick", "rim"), ("ride",)),
    ((42,), ("closed", "hat 1 cl"), ("ride",)),
    ((44,), ("pedal", "hat 1 pd"), ()),
    ((46,), ("open", "hat 1 op"), ("semi",)),
    ((50,), ("tom hi", "tom high", "tom 1", "high tom", "tomhi"), ()),
    ((47, 48), ("tom mid", "tom 2", "middle tom", "tom"), ("floor", "low", "hi", "kick")),
    ((41, 43, 45), ("tom low", "floor", "low tom"), ()),
    ((49, 52, 55, 57), ("crash",), ("ride",)),
    ((51, 59), ("ride",), ("bell", "cup")),
    ((53,), ("bell", "cup"), ()),
)


def _text(el: ET.Element, tag: str, default: str = "") -> str:
    child = el.find(tag)
    return default if child is None or child.text is None else child.text


def hydrogen_sfz(folder: Path, cache: Path) -> Path:
    """An SFZ file (written in ``cache``) playing the Hydrogen drumkit in ``folder``."""
    root = ET.parse(folder / "drumkit.xml").getroot()
    ns = re.match(r"\{.*\}", root.tag)
    prefix = ns.group(0) if ns else ""
    instruments = []
    absent: list[str] = []
    for inst in root.iter(f"{prefix}instrument"):
        name = _text(inst, f"{prefix}name").strip().lower()
        layers = []
        for layer in inst.iter(f"{prefix}layer"):
            fname = _text(layer, f"{prefix}filename")
            if not fname:
                continue
            if not (folder / fname).is_file():  # Millo_MultiLayered2 lists a cowbell it lacks
                absent.append(fname)
                continue
            lo = float(_text(layer, f"{prefix}min", "0"))
            hi = float(_text(layer, f"{prefix}max", "1"))
            layers.append((folder / fname, lo, hi))
        if not layers:  # old kits: one sample per instrument
            fname = _text(inst, f"{prefix}filename")
            if fname:
                layers.append((folder / fname, 0.0, 1.0))
        volume = float(_text(inst, f"{prefix}volume", "1") or 1)
        if layers:
            instruments.append((name, layers, volume))
    if absent:
        log.info(
            "%s: %d sample files absent (%s), their layers skipped",
            folder.name,
            len(absent),
            ", ".join(sorted(set(absent))),
        )
    lines = []
    used: set[int] = set()
    taken: set[str] = set()
    for notes, words, nots in ROLES:
        if set(notes) & used:
            continue
        pick = next(
            (
                i
                for i in instruments
                if i[0] not in taken
                and any(w in i[0] for w in words)
                and not any(x in i[0] for x in nots)
            ),
            None,
        )
        if pick is None:
            continue
        name, layers, volume = pick
        taken.add(name)
        used.update(notes)
        gain_db = 20 * np.log10(max(volume, 1e-3))
        for note in notes:
            for path, lo, hi in layers:
                lovel = max(1, min(127, round(lo * 127) + 1))
                hivel = max(lovel, min(127, round(hi * 127)))
                if lo <= 0.0:
                    lovel = 1
                extra = " group=1" if note == 42 or note == 44 else ""
                extra += " off_by=1" if note == 46 else ""
                lines.append(
                    f"<region> sample={path} key={note} pitch_keycenter={note} "
                    f"lovel={lovel} hivel={hivel} volume={gain_db:.2f}{extra}"
                )
    cache.mkdir(parents=True, exist_ok=True)
    out = cache / f"{folder.name.replace(' ', '_')}.sfz"
    out.write_text("\n".join(lines) + "\n")
    return out


def renderer(kit: KitSource, cache: Path) -> Callable[[np.ndarray, float, int], np.ndarray]:
    """``play(onsets, duration_s, sr)`` → mono float64 (n,) of the kit."""
    if kit.kind == "builtin":
        from livedrummer.audio.mix import mix_onsets

        def play_builtin(onsets: np.ndarray, duration_s: float, sr: int) -> np.ndarray:
            out: np.ndarray = mix_onsets(onsets, duration_s, None, sr).mean(axis=1)
            return out.astype(np.float64)

        return play_builtin
    if kit.kind == "sf2":
        from livedrummer.audio.soundfont import render_soundfont

        assert kit.path is not None

        def play_sf2(onsets: np.ndarray, duration_s: float, sr: int) -> np.ndarray:
            assert kit.path is not None
            out: np.ndarray = render_soundfont(onsets, duration_s, kit.path, sr).mean(axis=1)
            return out.astype(np.float64)

        return play_sf2
    from livedrummer.audio.sfz_render import render_sfz

    assert kit.path is not None
    sfz = hydrogen_sfz(kit.path, cache) if kit.kind == "hydrogen" else kit.path

    def play_sfz(onsets: np.ndarray, duration_s: float, sr: int) -> np.ndarray:
        out: np.ndarray = render_sfz(onsets, duration_s, sfz, sr).mean(axis=1)
        return out.astype(np.float64)

    return play_sfz
