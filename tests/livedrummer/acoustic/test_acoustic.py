"""The percussion recogniser on real drum samples: GMD grooves through Debian's TimGM6mb.

Audio comes from :mod:`services.bench._drumaudio` (FluidSynth, a room, noise, one-mic stems
with crosstalk; seeded). The accuracy floors are on a held-out (test-split) file and sit below
what ``livedrummer bench transcribe`` measures (docs/benchmarks/acoustic.md); the online detector is checked
against its offline twin by feeding random block sizes.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import wave
from pathlib import Path

import numpy as np
import pytest

from livedrummer.acoustic.detector import HIT_DTYPE, OnlineDetector, detect, tail_samples
from livedrummer.acoustic.pieces import CLASSES, parse_channel_map
from livedrummer.acoustic.profile import AudioProfileError, load_profile, parse_profile
from livedrummer.acoustic.score import score
from livedrummer.acoustic.spectrum import HOP
from livedrummer.errors import LivedrummerError
from services.bench._drumaudio import DEFAULT_SF2, MICS, SR, excerpt, render_mix, render_stems
from services.bench._kitcorpus import GROUPS_MIX

REPO = Path(__file__).resolve().parents[3]
HELD_OUT = "drummer1/eval_session/7_pop-groove7_138_beat_4-4.mid"  # split "test" in info.csv


@pytest.fixture(scope="module")
def sf2() -> Path:
    if not DEFAULT_SF2.is_file():
        reason = f"{DEFAULT_SF2} missing (Debian: apt-get install timgm6mb-soundfont)"
        if os.environ.get("CI"):
            pytest.fail(reason)
        pytest.skip(reason)
    return DEFAULT_SF2


@pytest.fixture(scope="module")
def held_out(groove_dir: Path, sf2: Path):  # type: ignore[no-untyped-def]
    ex = excerpt(groove_dir / HELD_OUT, 4.0, 12.0)
    return ex, render_mix(ex, sf2, seed=3), render_stems(ex, sf2, seed=3)


def _write_wav(path: Path, audio: np.ndarray, sr: int = SR) -> Path:
    data = audio if audio.ndim == 2 else audio[:, None]
    with wave.open(str(path), "wb") as w:
        w.setnchannels(data.shape[1])
        w.setsampwidth(2)
        w.setframerate(sr)
        w.writeframes(np.round(np.clip(data, -1, 1) * 32767).astype("<i2").tobytes())
    return path


def _online(det: OnlineDetector, audio: np.ndarray, seed: int) -> tuple[np.ndarray, list[int]]:
    """Hits fed in random blocks, and the sample count fed when each hit came out."""
    rng = np.random.default_rng(seed)
    pad = np.zeros((tail_samples(det.profile.settings.lookahead), *audio.shape[1:]))
    data = np.concatenate([audio, pad])
    out, fed_at, pos = [], [], 0
    while pos < len(data):
        n = int(rng.integers(1, 3000))
        hits = det.process(data[pos : pos + n])
        pos += n
        out.append(hits)
        fed_at += [min(pos, len(data))] * len(hits)
    return np.concatenate(out) if out else np.zeros(0, HIT_DTYPE), fed_at


def test_online_twin_gives_the_offline_hits_within_its_latency(held_out) -> None:  # type: ignore[no-untyped-def]
    _ex, mix, (stems, names) = held_out
    profile = load_profile(None)
    clip = mix[: 6 * SR]
    offline = detect(clip, SR, profile)
    det = OnlineDetector(profile, SR)
    online, fed_at = _online(det, clip, seed=1)
    assert len(offline) > 20
    np.testing.assert_array_equal(online, offline)
    # each hit is out once the samples up to its decision frame are in: the attack's frame
    # (time + offset, rounded up to a frame end) plus the lookahead
    latency = (profile.settings.lookahead + 1) * HOP + profile.settings.offset_ms * SR / 1000
    for hit, fed in zip(online, fed_at, strict=True):
        assert fed - hit["time_s"] * SR <= latency + 3000  # + the block that carried it
    det.reset()
    again, _ = _online(det, clip, seed=2)
    np.testing.assert_array_equal(again, offline)
    chans = [CLASSES.index(MICS[n][0]) for n in names]
    offline_m = detect(stems[: 6 * SR], SR, profile, chans)
    online_m, _ = _online(OnlineDetector(profile, SR, chans), stems[: 6 * SR], seed=3)
    assert len(offline_m) > 20
    np.testing.assert_array_equal(online_m, offline_m)


def test_mix_accuracy_on_a_held_out_groove(held_out) -> None:  # type: ignore[no-untyped-def]
    ex, mix, _ = held_out
    hits = detect(mix, SR, load_profile(None))
    s = score(
        hits["time_s"],
        hits["cls"],
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        GROUPS_MIX,
    )
    assert s["kick"].tp + s["kick"].fn > 10 and s["snare"].tp + s["snare"].fn > 10
    assert s["kick"].f >= 0.80, s["kick"]  # measured 0.895 (kick, 21 onsets)
    assert s["snare"].f >= 0.80, s["snare"]  # 0.917 (13)
    assert s["hihat"].f >= 0.85, s["hihat"]  # 0.926 (55)
    # times: matched hits within a few ms of the MIDI
    truth = ex.onsets["time_s"][ex.classes == CLASSES.index("kick")]
    kicks = hits["time_s"][hits["cls"] == CLASSES.index("kick")]
    err = [np.min(np.abs(truth - t)) for t in kicks]
    assert np.median(err) < 0.004


def test_a_hihat_just_after_a_loud_snare_is_a_hit_of_its_own(held_out) -> None:  # type: ignore[no-untyped-def]
    """The hi-hat 8 ms after a full-strength snare: in a mix, inside the full-band picking window
    of the snare's onset, found by the high-band onset function (as a hi-hat, not a 2nd snare);
    with one microphone each, on the hat's channel behind the snare's crosstalk."""
    from dataclasses import replace

    ex = held_out[0]
    snare = ex.onsets[ex.classes == CLASSES.index("snare")][:1].copy()
    hat = ex.onsets[ex.classes == CLASSES.index("hihat_closed")][:1].copy()
    snare["time_s"], snare["velocity"] = 0.25, 127
    hat["time_s"], hat["velocity"] = 0.258, 100
    pair = replace(
        ex,
        onsets=np.concatenate([snare, hat]),
        duration_s=0.8,
        classes=np.array([CLASSES.index("snare"), CLASSES.index("hihat_closed")]),
    )
    hits = detect(render_mix(pair, seed=5), SR, load_profile(None))
    got = sorted((CLASSES[int(h["cls"])], round(float(h["time_s"]), 3)) for h in hits)
    assert [c for c, _t in got] == ["hihat_closed", "snare"], got
    assert all(abs(t - want) < 0.010 for (_c, t), want in zip(got, (0.258, 0.25), strict=True)), got
    # one microphone each: the hat's, hearing the snare 20 dB down, still hears its own hat
    hat["velocity"] = 100
    pair = replace(pair, onsets=np.concatenate([snare, hat]))
    stems, names = render_stems(pair, seed=5)
    assert names == ["snare", "hihat"]
    hits = detect(
        stems, SR, load_profile(None), [CLASSES.index("snare"), CLASSES.index("hihat_closed")]
    )
    got = sorted(
        (CLASSES[int(h["cls"])], int(h["channel"]), round(float(h["time_s"]), 3)) for h in hits
    )
    assert [(c, ch) for c, ch, _t in got] == [("hihat_closed", 1), ("snare", 0)], got


def test_a_crash_on_a_snare_stroke_is_found_and_its_ring_is_no_stroke(held_out) -> None:  # type: ignore[no-untyped-def]
    """One microphone per drum: a crash struck 8 ms after a full-strength snare is first heard
    on its microphone as the snare's crosstalk; the second look after the dropped crosstalk
    finds it, and its ring wobbling on (TimGM6mb's crash bumps 150-300 ms after a stroke) is
    no stroke, nor is the noise starting with the file. Before, the crash's channel missed the
    crash and heard the wobble as strokes."""
    from dataclasses import replace

    from livedrummer.midi.notemap import load_note_map

    ex = held_out[0]
    snare = ex.onsets[ex.classes == CLASSES.index("snare")][:2].copy()
    crash = snare[:1].copy()
    spec = load_note_map("general-midi").notes[49]
    crash["note"], crash["instrument"] = 49, spec.instrument_code
    crash["zone"], crash["hihat"] = spec.zone.code, spec.hihat.code
    snare["time_s"], snare["velocity"] = (0.25, 1.25), 127
    crash["time_s"], crash["velocity"] = 0.258, 100
    codes = [CLASSES.index("snare"), CLASSES.index("crash")]
    pair = replace(
        ex,
        onsets=np.concatenate([snare, crash]),
        duration_s=2.0,
        classes=np.array([codes[0], codes[0], codes[1]]),
    )
    stems, names = render_stems(pair, seed=5)
    assert names == ["snare", "crash"]
    hits = detect(stems, SR, load_profile(None), codes)
    got = [(CLASSES[int(h["cls"])], round(float(h["time_s"]), 3)) for h in hits]
    assert [c for c, _t in got] == ["snare", "crash", "snare"], got
    assert abs(got[1][1] - 0.258) < 0.012, got
    # the second look reads only frames the decision waits for: the online twin agrees
    online, _ = _online(OnlineDetector(load_profile(None), SR, codes), stems, seed=6)
    np.testing.assert_array_equal(online, hits)


def test_one_mic_per_drum_accuracy_and_crosstalk(held_out) -> None:  # type: ignore[no-untyped-def]
    ex, _, (stems, names) = held_out
    profile = load_profile(None)
    chans = [CLASSES.index(MICS[n][0]) for n in names]
    hits = detect(stems, SR, profile, chans)
    groups = {n: MICS[n] for n in names}
    s = score(
        hits["time_s"], hits["cls"], ex.onsets["time_s"], ex.classes, ex.onsets["velocity"], groups
    )
    assert s["kick"].f >= 0.95, s["kick"]  # measured 1.000
    assert s["snare"].f >= 0.92, s["snare"]  # 1.000
    assert s["hihat"].f >= 0.95, s["hihat"]  # 0.991
    # without crosstalk rejection (leak 0) the kick's leak shows up on the other mics
    import dataclasses

    loose = dataclasses.replace(profile, settings=dataclasses.replace(profile.settings, leak=0.0))
    raw = detect(stems, SR, loose, chans)
    assert len(raw) > len(hits) + 10
    # velocity follows the MIDI velocity (louder hits, higher velocity)
    kick = CLASSES.index("kick")
    truth = ex.onsets[ex.classes == kick]
    found = hits[hits["cls"] == kick]
    pairs = [
        (
            int(t["velocity"]),
            int(found["velocity"][np.argmin(np.abs(found["time_s"] - t["time_s"]))]),
        )
        for t in truth
    ]
    assert np.corrcoef(np.array(pairs).T)[0, 1] > 0.5


def test_a_ringing_rides_wobble_is_no_stroke_and_its_soft_strokes_are(
    groove_dir: Path, sf2: Path
) -> None:
    """A ride's microphone (one mic per drum): the ringing cymbal's wobble 100-200 ms after a
    stroke is no hit, a soft stroke on the ring is one. A tuning (train-split) groove with both;
    before the ride's lower floor and level check, the ride's channel heard 4 false strokes
    in it (and found every stroke)."""
    ex = excerpt(groove_dir / "drummer9/session1/23_rock_120_beat_4-4.mid", 5.0, 15.0)
    stems, names = render_stems(ex, sf2, seed=14)
    chans = [CLASSES.index(MICS[n][0]) for n in names]
    hits = detect(stems, SR, load_profile(None), chans)
    s = score(
        hits["time_s"],
        hits["cls"],
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        {"ride": ("ride",)},
    )["ride"]
    assert s.tp == 11 and s.fn == 0 and s.fp <= 1, s  # measured 11, 0, 1


def test_scoring_counts_as_documented() -> None:
    kick, snare, hh = (CLASSES.index(c) for c in ("kick", "snare", "hihat_closed"))
    ref_t = np.array([1.0, 1.02, 2.0, 3.0, 4.0, 5.0])
    ref_c = np.array([kick, kick, kick, snare, snare, -1])
    ref_v = np.array([100, 100, 100, 100, 10, 64])  # the 4.0 snare is 40 dB down: a ghost
    det_t = np.array([1.01, 2.03, 3.02, 4.0, 5.0, 6.0])
    det_c = np.array([kick, kick, snare, snare, hh, hh])
    s = score(det_t, det_c, ref_t, ref_c, ref_v)
    # 1.0 and 1.02 are one onset (merged); 2.03 is 30 ms late (a miss and a false alarm)
    assert (s["kick"].tp, s["kick"].fp, s["kick"].fn) == (1, 1, 1)
    # the ghost at 4.0 is don't care: its detection is neither hit nor false alarm
    assert (s["snare"].tp, s["snare"].fp, s["snare"].fn) == (1, 0, 0)
    # a detection on the unclassed (pedal) note is don't care; 6.0 is a false alarm
    assert (s["hihat_closed"].tp, s["hihat_closed"].fp, s["hihat_closed"].fn) == (0, 1, 0)
    assert s["all"].tp == 2


def test_profile_is_strict(tmp_path: Path) -> None:
    good = load_profile(None)
    text = good.to_toml()
    assert (
        parse_profile(__import__("tomllib").loads(text), "x.toml").templates.shape
        == good.templates.shape
    )
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("poly =", "polly ="))
    with pytest.raises(AudioProfileError, match=r"bad.toml: \[detector\] polly: unknown key"):
        load_profile(bad)
    bad.write_text(text.replace("[piece.kick]", "[piece.kik]"))
    with pytest.raises(AudioProfileError, match="kik: unknown drum"):
        load_profile(bad)
    bad.write_text(text.replace("templates = [\n  [", "templates = [\n  [1, ", 1))
    with pytest.raises(AudioProfileError, match="each template is a list of 28 numbers"):
        load_profile(bad)
    with pytest.raises(AudioProfileError, match="'nope' not found"):
        load_profile("nope")
    with pytest.raises(LivedrummerError, match="unknown drum 'cowbell'"):
        parse_channel_map("1=kick,2=cowbell")
    assert parse_channel_map("1=kick, 3=hihat") == {0: 0, 2: CLASSES.index("hihat_closed")}


@pytest.mark.parametrize(("name", "lookahead"), [("general-midi", 2), ("general-midi-fast", 1)])
def test_shipped_profile_is_the_soundfonts(sf2: Path, name: str, lookahead: int) -> None:
    """kits/audio/NAME.toml is what ``audio profile [--lookahead 1]`` makes from TimGM6mb
    today."""
    from livedrummer.acoustic.learn import soundfont_profile
    from livedrummer.acoustic.profile import DetectorSettings

    made = soundfont_profile(sf2, SR, settings=DetectorSettings(lookahead=lookahead))
    shipped = load_profile(name)
    assert shipped.settings == made.settings
    np.testing.assert_allclose(made.templates, shipped.templates, atol=1e-4)
    np.testing.assert_allclose(made.levels, shipped.levels, rtol=1e-4)


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "services", *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_transcribe_cli_writes_a_drum_file_inspect_reads(held_out, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    ex, mix, (stems, names) = held_out
    wav = _write_wav(tmp_path / "groove.wav", mix)
    out = tmp_path / "groove.mid"
    r = _cli("transcribe", str(wav), "-o", str(out), "--recogniser", "templates")
    assert r.returncode == 0, r.stderr
    assert "hits in 13.5 s (mix, profile general-midi)" in r.stdout
    r = _cli("transcribe", str(wav), "-o", str(tmp_path / "default.mid"))
    assert r.returncode == 0, r.stderr
    assert "hits in 13.5 s (mix, model " in r.stdout  # a mix's default: the learned model
    r = _cli("inspect", str(out), "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["map"] == "general-midi" and summary["onsets"] > 50
    # the file, read back as every command reads it, scores as the detector did
    from livedrummer.acoustic.pieces import classes_of
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.midi.smf import read_midi_file

    back = read_midi_file(out, load_note_map("general-midi")).onsets
    direct = detect(mix, SR, load_profile(None))
    assert len(back) == len(direct)
    np.testing.assert_allclose(back["time_s"], np.sort(direct["time_s"]), atol=0.0011)
    s = score(
        back["time_s"],
        classes_of(back),
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        GROUPS_MIX,
    )
    assert s["kick"].f >= 0.78 and s["snare"].f >= 0.78 and s["hihat"].f >= 0.6, s
    # one microphone per drum, from a multi-channel file
    wav = _write_wav(tmp_path / "stems.wav", stems)
    spec = ",".join(f"{i + 1}={n if n != 'hihat' else 'hihat'}" for i, n in enumerate(names))
    r = _cli("transcribe", str(wav), "-o", str(out), "--channels", spec)
    assert r.returncode == 0, r.stderr
    assert "one mic per drum" in r.stdout


def test_transcribe_bad_input_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from services.cli import main

    empty = tmp_path / "empty.wav"
    empty.write_bytes(b"")
    text = tmp_path / "notes.wav"
    text.write_text("not audio\n")
    silent = _write_wav(tmp_path / "silent.wav", np.zeros(SR))
    mono = _write_wav(tmp_path / "mono.wav", np.sin(np.arange(SR) / 3.0) * 0.5)
    out = str(tmp_path / "o.mid")
    cases = [
        (["transcribe", str(tmp_path / "missing.wav"), "-o", out], "missing.wav: no such file"),
        (["transcribe", str(empty), "-o", out], "empty.wav: not an audio file FFmpeg can read"),
        (["transcribe", str(text), "-o", out], "notes.wav: not an audio file FFmpeg can read"),
        (["transcribe", str(silent), "-o", out], "silent.wav: silent (peak digital silence)"),
        (["transcribe", str(mono), "-o", out, "--channels", "2=snare"], "channel 2 named, but"),
        (["transcribe", str(mono), "-o", out, "--channels", "kick"], "is not CHANNEL=DRUM"),
        (["transcribe", str(mono), "-o", out, "--audio-profile", "nope"], "'nope' not found"),
    ]
    capsys.readouterr()
    for argv, message in cases:
        assert main(argv) == 2, argv
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], (argv, lines)
    # through the installed entry point too: one line, status 2
    r = _cli("transcribe", str(empty), "-o", out)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    clipped = _write_wav(tmp_path / "loud.wav", np.clip(np.sin(np.arange(SR) / 3.0) * 3, -1, 1))
    assert main(["transcribe", str(clipped), "-o", out]) == 0
    err = capsys.readouterr().err
    assert "samples clipped" in err and len(err.strip().splitlines()) == 1


def test_noise_starting_out_of_silence_is_no_hit_and_a_drum_out_of_silence_is(held_out) -> None:  # type: ignore[no-untyped-def]
    """A file's or a player's start: noise 60 dB down beginning at sample 0 or after digital
    silence makes no hit, in a mix or on a microphone (a drum's, or a cymbal's with its lower
    thresholds: before, the crash's and the ride's heard the noise start); a snare out of
    silence is one."""
    from livedrummer.audio.soundfont import render_soundfont

    rng = np.random.default_rng(4)
    noise = 0.001 * rng.standard_normal(SR // 2)  # -60 dBFS: a quiet microphone
    for audio in (noise, np.concatenate([np.zeros(SR // 3), noise])):
        assert len(detect(audio, SR, load_profile(None))) == 0
        two = np.stack([audio, np.roll(audio, 7)], axis=1)
        assert len(detect(two, SR, load_profile(None), [0, 1])) == 0
        cymbals = [CLASSES.index("crash"), CLASSES.index("ride")]
        assert len(detect(two, SR, load_profile(None), cymbals)) == 0
    snare = held_out[0].onsets[held_out[0].classes == CLASSES.index("snare")][:1].copy()
    snare["time_s"], snare["velocity"] = 0.2, 100
    clean = render_soundfont(snare, 0.6, DEFAULT_SF2, SR).mean(axis=1)
    clean[: int(np.argmax(np.abs(clean) > 1e-4))] = 0.0  # digital silence up to the stroke
    hits = detect(clean, SR, load_profile(None))
    assert [CLASSES[int(c)] for c in hits["cls"]] == ["snare"], hits
    assert abs(float(hits["time_s"][0]) - 0.2) < 0.005, hits


def test_steady_noise_is_no_hit_and_the_hats_in_it_are(held_out) -> None:  # type: ignore[no-untyped-def]
    """A steady hiss's jitter rises in the log spectrum as much at -30 dBFS as at -50, most in
    the high bands: before the level-lift checks, 10 s of white noise at -30 dBFS gave a
    hi-hat's microphone 56 hits, a ride's 23 and a mix 79. A struck hat lifts the level, so the
    held-out groove's hi-hat microphone with noise 30 dB under its loudest stroke still finds
    its strokes (before: 14 false hits)."""
    profile = load_profile(None)
    noise = 0.03 * np.random.default_rng(5).standard_normal(10 * SR)  # -30 dBFS
    assert len(detect(noise, SR, profile)) <= 12  # measured 9
    for drum, most in (("hihat_closed", 1), ("ride", 10)):  # measured 1, 8
        assert len(detect(noise[:, None], SR, profile, [CLASSES.index(drum)])) <= most, drum
    ex, _, (stems, names) = held_out
    hat = stems[:, names.index("hihat")].astype(np.float64)
    noisy = hat + 10 ** (-50 / 20) * np.random.default_rng(6).standard_normal(len(hat))
    hits = detect(noisy[:, None], SR, profile, [CLASSES.index("hihat_closed")])
    s = score(
        hits["time_s"],
        hits["cls"],
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        {"hihat": MICS["hihat"]},
    )["hihat"]
    assert s.tp >= 53 and s.fp <= 6, s  # measured 54 found, 5 false, 1 missed


@pytest.mark.parametrize(("note", "drum"), [(37, "snare"), (53, "ride")])
def test_a_side_stick_and_a_ride_bell_are_their_drums_strokes(
    sf2: Path, note: int, drum: str
) -> None:
    """The ground truth counts a side stick (GM 37) as a snare stroke and the ride's bell (53)
    as a ride stroke; they sound like no snare head and no ride bow, so the profile holds a
    template of its own for each (before, side sticks were heard as crashes, bells as a ride
    and an open hi-hat)."""
    from livedrummer.audio.soundfont import render_soundfont
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.timeline.events import ONSET_DTYPE

    spec = load_note_map("general-midi").notes[note]
    notes = np.zeros(6, ONSET_DTYPE)
    notes["time_s"] = 0.3 + 0.25 * np.arange(6)
    notes["note"], notes["velocity"] = note, (120, 100, 90, 75, 60, 110)
    notes["channel"], notes["instrument"] = 9, spec.instrument_code
    notes["zone"], notes["hihat"] = spec.zone.code, spec.hihat.code
    audio = render_soundfont(notes, 2.0, sf2, SR).mean(axis=1)
    hits = detect(audio, SR, load_profile(None))
    mine = hits["cls"] == CLASSES.index(drum)
    assert len(hits[mine]) == 6, [CLASSES[c] for c in hits["cls"]]
    assert np.abs(hits[mine]["time_s"] - notes["time_s"]).max() < 0.01
    # (the side stick's high band rings on: a hi-hat of velocity 15-18 is heard 16 ms after
    # two of them)
    assert (hits[~mine]["velocity"] < 20).all(), hits


def test_a_lookahead_one_profile_decides_a_frame_sooner(held_out, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """``audio profile --lookahead 1``: its templates are read one frame after the onset, and
    its online detector gives its offline hits one frame (2.67 ms) sooner than the default."""
    ex, mix, _ = held_out
    out = _cli(
        "audio",
        "profile",
        "--soundfont",
        str(DEFAULT_SF2),
        "--lookahead",
        "1",
        "-o",
        str(tmp_path / "fast.toml"),
    )
    assert out.returncode == 0, out.stderr
    fast = load_profile(str(tmp_path / "fast.toml"))
    assert fast.settings.lookahead == 1
    assert not np.allclose(fast.templates, load_profile(None).templates)  # read sooner
    clip = mix[: 6 * SR]
    offline = detect(clip, SR, fast)
    online, fed_at = _online(OnlineDetector(fast, SR), clip, seed=4)
    assert len(offline) > 20
    np.testing.assert_array_equal(online, offline)
    decided = np.round((offline["time_s"] + fast.settings.offset_ms / 1000) * SR) + HOP
    fed = np.array(fed_at)
    assert (fed >= decided).all()  # no hit before its decision frame is in
    assert (fed - decided < 3000).all()  # and out with the block that carried that frame
    hits = detect(mix, SR, fast)
    s = score(
        hits["time_s"],
        hits["cls"],
        ex.onsets["time_s"],
        ex.classes,
        ex.onsets["velocity"],
        GROUPS_MIX,
    )
    # measured kick 0.895, snare 0.870, hi-hat 0.933
    assert s["kick"].f >= 0.80 and s["snare"].f >= 0.80 and s["hihat"].f >= 0.80, s
    bad = _cli(
        "audio",
        "profile",
        "--soundfont",
        str(DEFAULT_SF2),
        "--lookahead",
        "0",
        "-o",
        str(tmp_path / "x.toml"),
    )
    assert bad.returncode == 2 and bad.stderr.strip().count("\n") == 0, bad.stderr
    assert "--lookahead" in bad.stderr
