"""The drum track from a SoundFont: real FluidSynth on a SoundFont 2 file written by the test.

The SoundFont (:mod:`sf2_writer`) has one drum preset whose every key plays a 440 Hz cosine
burst at root key 60, so attacks, levels and pitches in FluidSynth's output can be measured; a
second one rings for seconds after its note-off, as a cymbal does, for the chokes.
Without libfluidsynth3 these tests skip on a developer's machine and fail under CI.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import av
import mido
import numpy as np
import pytest
from sf2_writer import write_sf2

from livedrummer.audio.mix import GRAB_FADE_S
from livedrummer.audio.soundfont import check_soundfont, render_soundfont
from livedrummer.kit.loader import load_kit
from livedrummer.midi.gm import gm_note
from livedrummer.midi.notemap import load_note_map
from livedrummer.timeline.events import ONSET_DTYPE, Onset
from services.cli import main
from tests.services.cli.test_render_export import choked_crash, crash_rms_around_the_grab, read_back

SR = 48_000
REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module", autouse=True)
def needs_fluidsynth() -> None:
    try:
        import fluidsynth  # noqa: F401
    except (ImportError, OSError) as exc:
        reason = f"FluidSynth not loadable ({exc}; Debian: apt-get install libfluidsynth3)"
        if os.environ.get("CI"):  # CI's set-up installs every real part (as conftest does)
            pytest.fail(reason)
        pytest.skip(reason)


@pytest.fixture(scope="module")
def sf2(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_sf2(tmp_path_factory.mktemp("sf") / "tiny.sf2")


@pytest.fixture(scope="module")
def ringing_sf2(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """440 Hz for 3 s, decaying slowly, with an 8 s release: a note-off does not stop it."""
    t = np.arange(3 * SR) / SR
    wave = 0.8 * np.cos(2 * np.pi * 440.0 * t) * np.exp(-t / 1.5)
    sample = np.round(wave * 32767).astype("<i2")
    return write_sf2(tmp_path_factory.mktemp("sf") / "ringing.sf2", sample, release_s=8.0)


def onsets(hits: list[tuple[float, int, int]], map_name: str = "general-midi") -> np.ndarray:
    """(time_s, note, velocity) hits as onsets, each note read through the named map."""
    note_map = load_note_map(map_name)
    rows = []
    for t, note, vel in hits:
        spec = note_map.lookup(note)
        assert spec is not None, note
        rows.append(
            Onset(t, note, vel, 9, spec.instrument, spec.zone, spec.hihat, math.nan).to_record()
        )
    return np.array(rows, ONSET_DTYPE)


def attack_s(env: np.ndarray, t: float, rate: int, before_s: float, after_s: float) -> float:
    """Time of the first sample near ``t`` above a fifth of that neighbourhood's peak."""
    lo = max(0, int((t - before_s) * rate))
    window = env[lo : int((t + after_s) * rate)]
    return (lo + int(np.argmax(window > 0.2 * window.max()))) / rate


def test_writer_makes_a_soundfont_fluidsynth_loads(sf2: Path) -> None:
    check_soundfont(sf2)  # raises SoundFontError when FluidSynth refuses it


def test_attacks_land_on_the_onsets_and_nothing_sounds_before(sf2: Path) -> None:
    times = [0.1234, 0.3071, 0.5555, 0.8013]  # deliberately off FluidSynth's 64-sample blocks
    hits = onsets([(t, note, 100) for t, note in zip(times, [36, 38, 42, 60], strict=True)])
    audio = render_soundfont(hits, 1.2, sf2, SR)
    assert audio.shape == (round(1.2 * SR), 2) and audio.dtype == np.float32
    env = np.abs(audio).max(axis=1)
    assert env.max() > 0.05
    assert env[: int((times[0] - 0.001) * SR)].max() < 1e-4  # silence before the first hit
    for t in times:
        got = attack_s(env, t, SR, 0.005, 0.02)
        assert abs(got - t) < 0.002, (t, got)


def test_a_harder_stroke_is_louder(sf2: Path) -> None:
    times, velocities = [0.1, 0.45, 0.8], [30, 80, 127]
    audio = render_soundfont(onsets(list(zip(times, [38] * 3, velocities, strict=True))), 1.2, sf2)
    env = np.abs(audio).max(axis=1)
    peaks = [env[int(t * SR) : int((t + 0.1) * SR)].max() for t in times]
    assert peaks[0] < peaks[1] < peaks[2], peaks
    assert peaks[0] > 1e-3


@pytest.mark.parametrize("note", [48, 60, 67, 72])
def test_pitch_follows_the_key_relative_to_the_root(sf2: Path, note: int) -> None:
    audio = render_soundfont(onsets([(0.05, note, 110)]), 0.3, sf2)
    piece = audio[int(0.06 * SR) : int(0.14 * SR), 0].astype(np.float64)
    spectrum = np.abs(np.fft.rfft(piece * np.hanning(piece.size), n=1 << 17))
    peak_hz = float(np.argmax(spectrum)) * SR / (1 << 17)
    expected = 440.0 * 2 ** ((note - 60) / 12)
    assert peak_hz == pytest.approx(expected, rel=0.01)


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x, dtype=np.float64))))


def test_a_grab_stops_a_ringing_cymbal_after_a_short_fade(ringing_sf2: Path) -> None:
    kit = load_kit("rock5")
    grab, again = 0.6, 1.3
    hits = onsets([(0.1, 49, 110), (again, 49, 110)])  # GM 49: crash 1
    chokes = [np.array([grab]) if p.name == "crash1" else np.zeros(0) for p in kit.pieces]
    free = render_soundfont(hits, 2.0, ringing_sf2, SR)
    choked = render_soundfont(hits, 2.0, ringing_sf2, SR, kit, chokes)
    g, f, a = round(grab * SR), round(GRAB_FADE_S * SR), round(again * SR)
    np.testing.assert_allclose(choked[:g], free[:g], atol=1e-5)  # the same up to the grab
    assert rms(free[g + f : a]) > 0.01  # the note-off at 0.2 s did not stop it ...
    assert rms(choked[g + f : a]) < 1e-5  # ... the grab did, after a fade, not a step:
    gain = choked[g : g + f, 0] / free[g : g + f, 0]
    ramp = np.linspace(1.0, 0.0, f)
    loud = np.abs(free[g : g + f, 0]) > 0.05  # a ratio means something where there is sound
    np.testing.assert_allclose(gain[loud], ramp[loud], atol=1e-3)
    assert (
        np.abs(np.diff(choked[g - f : g + f + 1, 0])).max()
        <= np.abs(np.diff(free[g - f : g + f + 1, 0])).max() + 1e-4
    )
    # the stroke after the grab sounds as if alone (the free track has the first one's tail)
    alone = render_soundfont(hits[1:], 2.0, ringing_sf2, SR)
    np.testing.assert_allclose(choked[a:], alone[a:], atol=1e-5)


def test_strokes_after_an_earlier_grab_keep_their_attack_on_the_onset(ringing_sf2: Path) -> None:
    # Two groups through the second synth; the first ends 5 ms after a grab that is not on a
    # 64-sample block, and the second's stroke must still start on its own sample: from its
    # second block on it is the stroke played alone (its first block, a voice FluidSynth used
    # before, differs a little; see the module docstring of livedrummer.audio.soundfont).
    kit = load_kit("rock5")
    hits = onsets([(0.1, 49, 110), (0.9, 49, 110)])
    grabs = np.array([0.6013, 1.5])
    chokes = [grabs if p.name == "crash1" else np.zeros(0) for p in kit.pieces]
    choked = render_soundfont(hits, 2.0, ringing_sf2, SR, kit, chokes)
    alone = render_soundfont(hits[1:], 2.0, ringing_sf2, SR)
    window = slice(round(0.9 * SR) + 64, round(1.5 * SR))
    np.testing.assert_allclose(choked[window], alone[window], atol=1e-5)


def test_e_kit_notes_sound_as_their_general_midi_equivalents() -> None:
    roland = load_note_map("roland-td")
    expect = {22: 42, 26: 46, 48: 50, 50: 50, 45: 48, 40: 38, 55: 49, 59: 51, 36: 36, 38: 38}
    got = {}
    for note in expect:
        spec = roland.lookup(note)
        assert spec is not None
        got[note] = gm_note(note, spec.instrument, spec.zone, spec.hihat)
    assert got == expect
    gm = load_note_map("general-midi")  # a GM file keeps every one of its notes
    kept = [n for n, s in gm.notes.items() if gm_note(n, s.instrument, s.zone, s.hihat) == n]
    assert sorted(kept) == sorted(gm.notes)


@pytest.fixture
def tiny_mid(write_midi) -> Path:  # type: ignore[no-untyped-def]
    msgs: list[mido.Message] = [mido.MetaMessage("set_tempo", tempo=500_000, time=0)]
    for delta, note, vel in [(0, 36, 110), (240, 38, 100), (360, 42, 90), (480, 49, 120)]:
        msgs.append(mido.Message("note_on", channel=9, note=note, velocity=vel, time=delta))
        msgs.append(mido.Message("note_off", channel=9, note=note, velocity=0, time=30))
    path: Path = write_midi(msgs, name="tiny.mid")
    return path


def test_render_cli_puts_the_soundfont_track_in_the_video(
    tiny_mid: Path, sf2: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from livedrummer.midi.smf import read_midi_file
    from services.display.context import DisplayError, headless_context

    try:
        headless_context().release()
    except DisplayError as exc:
        pytest.skip(str(exc))  # as tests/services/cli/test_render_export.py: no EGL, no video
    out = tmp_path / "out.mp4"
    fps = 30
    code = main(
        [
            "render",
            str(tiny_mid),
            "-o",
            str(out),
            "--size",
            "160x90",
            "--fps",
            str(fps),
            "--tail",
            "0.5",
            "--camera",
            "front",
            "--soundfont",
            str(sf2),
        ]
    )
    assert code == 0
    assert f"from {sf2}" in capsys.readouterr().out
    with av.open(str(out)) as c:
        stream = c.streams.audio[0]
        audio = np.concatenate([f.to_ndarray() for f in c.decode(stream)], axis=1).T
        rate = stream.rate
    env = np.abs(audio).max(axis=1)
    times = read_midi_file(tiny_mid, load_note_map("general-midi")).onsets["time_s"]
    for t in times:
        got = attack_s(env, float(t), rate, 1 / fps, 1 / fps)
        assert abs(got - t) < 1 / fps, (t, got)
    # The kick is the SoundFont's tone at GM note 36, two octaves below its root 60:
    # 440 * 2**(-24/12) = 110 Hz, not the built-in kick.
    piece = audio[int(times[0] * rate) : int((times[0] + 0.2) * rate), 0].astype(np.float64)
    spectrum = np.abs(np.fft.rfft(piece * np.hanning(piece.size), n=1 << 17))
    assert float(np.argmax(spectrum)) * rate / (1 << 17) == pytest.approx(110.0, rel=0.02)


def test_render_cli_stops_a_choked_crash_in_the_soundfont_track(
    write_midi,
    ringing_sf2: Path,
    tmp_path: Path,  # type: ignore[no-untyped-def]
) -> None:
    from services.display.context import DisplayError, headless_context

    try:
        headless_context().release()
    except DisplayError as exc:
        pytest.skip(str(exc))
    out = tmp_path / "out.mp4"
    code = main(["render", str(choked_crash(write_midi)), "-o", str(out), "--size", "96x54",
                 "--fps", "10", "--tail", "1.0", "--camera", "front",
                 "--soundfont", str(ringing_sf2)])  # fmt: skip
    assert code == 0
    _frames, _video_s, audio, rate, _size = read_back(out)
    before, after = crash_rms_around_the_grab(audio, rate)
    assert before > 0.005  # the crash rings through its note-off up to the grab ...
    assert after < 0.02 * before, (before, after)  # ... and is silent after it


def _cli(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "services", *argv],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )


@pytest.mark.parametrize("kind", ["missing", "random", "truncated", "no-drum-kit"])
def test_a_bad_soundfont_is_one_line_naming_the_file(
    kind: str, sf2: Path, tiny_mid: Path, tmp_path: Path
) -> None:
    bad = tmp_path / f"{kind}.sf2"
    if kind == "random":
        bad.write_bytes(np.random.default_rng(5).bytes(4096))
    elif kind == "truncated":
        bad.write_bytes(sf2.read_bytes()[:-300])
    elif kind == "no-drum-kit":
        write_sf2(bad, bank=0)
    out = tmp_path / "out.mp4"
    done = _cli("render", str(tiny_mid), "-o", str(out), "--soundfont", str(bad))
    assert done.returncode == 2
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and str(bad) in lines[0] and "Traceback" not in done.stderr, lines
    assert not out.exists()  # failed before any video was started


def test_up_refuses_a_bad_soundfont_before_the_show(tmp_path: Path) -> None:
    missing = tmp_path / "nope.sf2"
    done = _cli(
        "up",
        "--demo",
        "--headless",
        "--seconds",
        "30",
        "--frames-dir",
        str(tmp_path / "live"),
        "--video",
        str(tmp_path / "show.mp4"),
        "--soundfont",
        str(missing),
    )
    assert done.returncode == 2
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and str(missing) in lines[0], lines
    assert not (tmp_path / "live").exists()
