"""Cymbal grabs and the closing hi-hat cut the live sound as they cut the offline render.

The controls are read into cuts once (:func:`sound_chokes`, offline) and one row at a time
(:class:`CutReader`, live); the live mixers, fed the onsets and the cuts in time order block by
block, give the offline track sample for sample: the built-in kit and an SFZ kit."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from livedrummer.audio.cuts import CutReader, sound_chokes
from livedrummer.audio.live_mix import LiveMixer
from livedrummer.audio.mix import mix_onsets
from livedrummer.kit.loader import load_kit
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, ControlKind

SR = 48_000
TIMGM = Path("/usr/share/sounds/sf2/TimGM6mb.sf2")
SECONDS = 1.6
# (time, note, instrument, zone, hihat articulation)
STROKES = [(0.05, 49, "crash1", Zone.BOW, HiHat.NONE), (0.1, 46, "hihat", Zone.BOW, HiHat.OPEN),
           (0.2, 51, "ride", Zone.BOW, HiHat.NONE), (0.62, 44, "hihat", Zone.PEDAL, HiHat.PEDAL),
           (0.8, 49, "crash1", Zone.BOW, HiHat.NONE), (0.9, 46, "hihat", Zone.BOW, HiHat.OPEN),
           (1.2, 42, "hihat", Zone.BOW, HiHat.CLOSED)]  # fmt: skip
# (time, kind, number, value): the pedal opens, the crash is grabbed and let go, the pedal
# closes just before its chick, opens, the crash is grabbed again, the pedal closes on the
# same instant as a closed stroke (the module sends CC4 first: the stroke is not cut)
CONTROLS = [(0.04, ControlKind.HIHAT_PEDAL, 4, 0), (0.4, ControlKind.CHOKE, 49, 127),
            (0.45, ControlKind.CHOKE, 49, 0), (0.6, ControlKind.HIHAT_PEDAL, 4, 127),
            (0.85, ControlKind.HIHAT_PEDAL, 4, 10), (1.0, ControlKind.CHOKE, 55, 127),
            (1.2, ControlKind.HIHAT_PEDAL, 4, 127)]  # fmt: skip


def strokes() -> np.ndarray:
    rows = np.zeros(len(STROKES), ONSET_DTYPE)
    for i, (t, note, piece, zone, hat) in enumerate(STROKES):
        rows[i] = (
            t,
            note,
            70,
            9,
            INSTRUMENTS.index(piece),
            ZONES.index(zone),
            HIHATS.index(hat),
            math.nan,
            0,
        )
    return rows


def controls() -> np.ndarray:
    rows = np.zeros(len(CONTROLS), CONTROL_DTYPE)
    for i, (t, kind, number, value) in enumerate(CONTROLS):
        rows[i] = (t, int(kind), 9, number, value, 0)
    return rows


def live(mixer: LiveMixer, kit: Kit, seed: int, with_controls: bool = True) -> np.ndarray:
    """Onsets and controls fed in time order (controls first at one instant, as a module sends
    them), each about 30 ms before it sounds; blocks of random sizes."""
    reader = CutReader(load_note_map("roland-td"), kit)
    events = sorted(
        [(float(r["time_s"]), 1, r) for r in strokes()]
        + [(float(r["time_s"]), 0, r) for r in controls() if with_controls],
        key=lambda e: (e[0], e[1]),
    )
    rng = np.random.default_rng(seed)
    n, blocks, k = round(SECONDS * SR), [], 0
    while mixer.rendered < n:
        size = int(rng.integers(32, 700))
        while k < len(events) and round(events[k][0] * SR) < mixer.rendered + size + 1440:
            t, is_onset, row = events[k]
            if is_onset:
                mixer.add(row, round(t * SR))
            elif (cut := reader.take(row)) is not None:
                mixer.cut(cut[0], cut[1], round(cut[1] * SR))
            k += 1
        blocks.append(mixer.render(size))
    return np.concatenate(blocks)[:n]


def cut_by_the_two(
    offline: np.ndarray, free: np.ndarray, render: Callable[[np.ndarray], np.ndarray]
) -> None:
    """The offline twin itself cuts: after the first grab only the hi-hat and the ride sound,
    after the pedal closes only the ride and the chick (as those alone would sound)."""
    on = strokes()
    grabbed = slice(round(0.41 * SR), round(0.59 * SR))
    np.testing.assert_allclose(offline[grabbed], render(on[[1, 2]])[grabbed], atol=1e-5)
    closed = slice(round(0.61 * SR), round(0.79 * SR))
    np.testing.assert_allclose(offline[closed], render(on[[2, 3]])[closed], atol=1e-5)
    assert np.abs(free[grabbed] - offline[grabbed]).max() > 0.05  # the crash rang there


def test_grabs_and_pedal_closings_become_cuts_per_piece() -> None:
    kit = load_kit("rock5")
    names = [p.name for p in kit.pieces]
    chokes = dict(
        zip(names, sound_chokes(controls(), load_note_map("roland-td"), kit), strict=True)
    )
    # the grabs (a release cuts nothing; 55 is the crash's edge), and two closings of the pedal
    # (the first row only says where it is; opening cuts nothing), just before their instants
    assert chokes["crash1"].tolist() == [0.4, 1.0]
    assert chokes["hihat"].tolist() == [math.nextafter(0.6, 0), math.nextafter(1.2, 0)]
    assert all(chokes[n].size == 0 for n in names if n not in ("crash1", "hihat"))


def test_the_live_kit_cuts_as_the_offline_mix_does() -> None:
    kit = load_kit("rock5")
    chokes = sound_chokes(controls(), load_note_map("roland-td"), kit)
    offline = mix_onsets(strokes(), SECONDS, kit, SR, chokes)
    free = mix_onsets(strokes(), SECONDS, kit, SR)
    assert np.abs(offline).max() < 0.9  # not scaled for headroom: the twins must agree exactly
    cut_by_the_two(offline, free, lambda rows: mix_onsets(rows, SECONDS, kit, SR))
    for seed in (1, 2):
        got = live(LiveMixer(kit, SR), kit, seed)
        end = len(offline) - round(0.01 * SR)  # the offline track fades out what its end cuts
        assert np.max(np.abs(got[:end] - offline[:end])) < 1e-5


@pytest.fixture
def sfz_kit(tmp_path: Path) -> Path:
    import soundfile as sf

    t = np.arange(round(2.0 * SR)) / SR
    for name, hz in (
        ("crash", 700.0),
        ("ride", 900.0),
        ("open", 1100.0),
        ("closed", 2100.0),
        ("pedal", 1700.0),
    ):
        sf.write(
            str(tmp_path / f"{name}.wav"),
            (0.3 * np.sin(2 * np.pi * hz * t) * np.exp(-t / 1.5)).astype(np.float32),
            SR,
        )
    path = tmp_path / "kit.sfz"
    path.write_text(
        "<region> key=49 sample=crash.wav\n<region> key=51 sample=ride.wav\n"
        "<group> group=1 off_by=2 ampeg_release=0.01\n<region> key=46 sample=open.wav\n"
        "<group> group=2\n<region> key=42 sample=closed.wav\n"
        "<region> key=44 sample=pedal.wav\n"
    )
    return path


def test_the_live_sfz_kit_cuts_as_the_offline_render_does(sfz_kit: Path) -> None:
    from livedrummer.audio.sfz_live import SfzLiveMixer
    from livedrummer.audio.sfz_render import check_sfz, render_sfz

    kit = load_kit("rock5")
    chokes = sound_chokes(controls(), load_note_map("roland-td"), kit)
    offline = render_sfz(strokes(), SECONDS, sfz_kit, SR, kit, chokes)
    free = render_sfz(strokes(), SECONDS, sfz_kit, SR, kit)
    assert np.abs(offline).max() < 0.9
    cut_by_the_two(offline, free, lambda rows: render_sfz(rows, SECONDS, sfz_kit, SR, kit))
    got = live(SfzLiveMixer(check_sfz(sfz_kit), kit, SR), kit, 3)
    np.testing.assert_allclose(got, offline, atol=1e-5)


def soundfont() -> Path:
    """TimGM6mb (deploy/system-deps.sh installs it): its crash rings for seconds, so a cut
    shows (the tiny SoundFonts the tests write stop at their note-off)."""
    try:
        import fluidsynth  # noqa: F401
    except (ImportError, OSError) as exc:
        if os.environ.get("CI"):
            pytest.fail(f"FluidSynth not loadable ({exc})")
        pytest.skip(f"FluidSynth not loadable ({exc})")
    if not TIMGM.is_file():
        pytest.skip(f"{TIMGM} missing (Debian: timgm6mb-soundfont)")
    return TIMGM


def test_the_live_soundfont_cuts_its_pieces_channel_and_sounds_as_offline_without_cuts() -> None:
    from livedrummer.audio.soundfont import render_soundfont
    from livedrummer.audio.soundfont_live import SoundFontLiveMixer

    path, kit = soundfont(), load_kit("rock5")
    free = render_soundfont(strokes(), SECONDS, path, SR, kit)
    mixer = SoundFontLiveMixer(path, kit, SR)
    try:  # each piece on its own channel: with no cut, the offline track sample for sample
        same = live(mixer, kit, 4, with_controls=False)
    finally:
        mixer.close()
    rms = float(np.sqrt(np.mean(free**2)))
    assert np.abs(free).max() < 0.9 and float(np.sqrt(np.mean((same - free) ** 2))) < 1e-4 * rms
    chokes = sound_chokes(controls(), load_note_map("roland-td"), kit)
    offline = render_soundfont(strokes(), SECONDS, path, SR, kit, chokes)
    mixer = SoundFontLiveMixer(path, kit, SR)
    try:
        got = live(mixer, kit, 5)
    finally:
        mixer.close()

    def rms_of(x: np.ndarray, a: float, b: float) -> float:
        return float(np.sqrt(np.mean(x[round(a * SR) : round(b * SR)] ** 2)))

    # the dry sound stops where the offline one does: after each cut the live stream is far
    # nearer the offline track than the uncut one (what is left is the cut piece's reverb)
    for a, b in ((0.42, 0.59), (0.62, 0.79), (1.02, 1.19)):
        near, far = rms_of(got - offline, a, b), rms_of(free - offline, a, b)
        print(f"{a}-{b} s: live - offline RMS {near:.2e}, uncut - offline {far:.2e}")
        assert near < 0.25 * far, (a, near, far)
    # and before the first cut it is the offline track but for the reverb (shared there)
    assert rms_of(got - offline, 0.0, 0.4) < 0.1 * rms_of(offline, 0.0, 0.4)


def test_a_cut_that_comes_after_its_sample_was_rendered_stops_the_sound_from_there() -> None:
    kit = load_kit("rock5")
    mixer = LiveMixer(kit, SR)
    crash = strokes()[:1]
    crash["time_s"] = 0.0
    mixer.add(crash[0], 0)
    before = mixer.render(4800)
    mixer.cut(mixer.piece_of("crash1"), 0.05, 2400)  # its sample went out 50 ms ago
    after = mixer.render(4800)
    fade = round(0.005 * SR)
    assert np.abs(before[-100:]).max() > 0.05  # it rang up to the cut's arrival
    assert np.abs(after[:10]).max() > 0.02 and np.all(after[fade:] == 0)  # then faded out
    half = fade // 2  # a fade, not a step
    assert np.abs(after[:half]).max() > 2 * np.abs(after[half:fade]).max()


def test_a_hihat_stroke_during_a_cuts_fade_does_not_lengthen_it() -> None:
    kit = load_kit("rock5")
    hat = strokes()[1:2]  # the open hi-hat
    hat["time_s"] = 0.0
    later = hat.copy()
    later["time_s"], later["hihat"] = 0.06, HIHATS.index(HiHat.CLOSED)
    mixer, alone = LiveMixer(kit, SR), LiveMixer(kit, SR)
    mixer.add(hat[0], 0)
    mixer.cut(mixer.piece_of("hihat"), 0.05, 2400)  # the pedal closes: faded out by 2640
    first = mixer.render(2500)
    mixer.add(later[0], 2880)  # struck after the fade, arriving during it
    alone.add(later[0], 2880)
    alone.render(2500)
    rest = mixer.render(2000) - alone.render(2000)  # the open hat's own sound from 2500 on
    assert np.abs(first[2300:2400]).max() > 0.01  # it rang to the cut
    assert np.all(rest[2640 - 2500 :] == 0), np.flatnonzero(rest[:, 0])[-3:]
