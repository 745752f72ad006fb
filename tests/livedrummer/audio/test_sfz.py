"""SFZ drum kits: the parser (strict, with file:line errors) and the sampler, on a kit the
test writes itself (WAV and FLAC samples made here with soundfile)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from livedrummer.audio.sfz import SfzError, load_sfz, note_number, parse_sfz
from livedrummer.audio.sfz_render import check_sfz, render_sfz
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat, Zone
from livedrummer.timeline.events import ONSET_DTYPE

SR = 48_000
REPO = Path(__file__).resolve().parents[3]


def tone(path: Path, hz: float, seconds: float, rate: int = SR, decay_s: float = 10.0) -> Path:
    t = np.arange(round(seconds * rate)) / rate
    sf.write(
        str(path),
        (0.5 * np.sin(2 * np.pi * hz * t) * np.exp(-t / decay_s)).astype(np.float32),
        rate,
    )
    return path


KIT = """// a small kit: kick, snare in two velocity layers and two round robins, hats
<control> default_path=samples/
<global> ampeg_release=0.02 loop_mode=one_shot
<group> key=36 volume=-3  /* the kick */
<region> sample=kick.wav
<group> key=d2 seq_length=2
<region> sample=snare a.wav hivel=90 seq_position=1
<region> sample=snare b.flac hivel=90 seq_position=2
<region> sample=snare loud.wav lovel=91 seq_length=1
<group> group=1 off_by=2 pan=-50
<region> key=46 sample=hat open.wav
<group> group=2
<region> key=42 sample=hat closed.wav amp_veltrack=80 tune=5
"""


@pytest.fixture
def kit(tmp_path: Path) -> Path:
    folder = tmp_path / "samples"
    folder.mkdir()
    tone(folder / "kick.wav", 60, 0.5)
    tone(folder / "snare a.wav", 200, 0.3)
    tone(folder / "snare b.flac", 300, 0.3, rate=44_100)
    tone(folder / "snare loud.wav", 400, 0.3)
    tone(folder / "hat open.wav", 1000, 2.0)
    tone(folder / "hat closed.wav", 2000, 0.1)
    path = tmp_path / "kit.sfz"
    path.write_text(KIT)
    return path


def onsets(hits: list[tuple[float, str, int]]) -> np.ndarray:
    rows = np.zeros(len(hits), ONSET_DTYPE)
    notes = {"kick": 36, "snare": 38, "hat_open": 46, "hat_closed": 42}
    for i, (t, name, vel) in enumerate(hits):
        rows[i]["time_s"], rows[i]["velocity"], rows[i]["note"] = t, vel, notes[name]
        rows[i]["instrument"] = INSTRUMENTS.index(name.split("_")[0].replace("hat", "hihat"))
        rows[i]["zone"] = ZONES.index(Zone.HEAD if name in ("kick", "snare") else Zone.BOW)
        hat = {"hat_open": HiHat.OPEN, "hat_closed": HiHat.CLOSED}.get(name, HiHat.NONE)
        rows[i]["hihat"] = HIHATS.index(hat)
        rows[i]["openness"] = math.nan
    return rows


def test_regions_inherit_their_group_and_global_and_unknown_opcodes_are_listed(kit: Path) -> None:
    sfz = load_sfz(kit)
    assert [r.sample.name for r in sfz.regions] == [
        "kick.wav",
        "snare a.wav",
        "snare b.flac",
        "snare loud.wav",
        "hat open.wav",
        "hat closed.wav",
    ]
    kick, snare_a, snare_b, loud, hat_open, hat_closed = sfz.regions
    assert kick.sample.parent == kit.parent / "samples" and kick.volume_db == -3.0
    assert (kick.lokey, kick.hikey, kick.keycenter, kick.loop_mode) == (36, 36, 36, "one_shot")
    assert (snare_a.lokey, snare_a.hivel, snare_a.seq_length, snare_a.seq_position) == (
        38,
        90,
        2,
        1,
    )
    assert snare_b.seq_position == 2 and loud.lovel == 91 and loud.release_s == 0.02
    assert (hat_open.group, hat_open.off_by, hat_open.pan) == (1, 2, -50.0)
    assert (hat_closed.group, hat_closed.off_by, hat_closed.tune_cents) == (2, 0, 5.0)
    assert hat_closed.line == 13 and hat_closed.sample_line == 13
    assert sfz.unknown == {"amp_veltrack": 13}
    assert [note_number(x) for x in ("c4", "C#4", "eb2", "60", "h3")] == [60, 61, 39, 60, None]


@pytest.mark.parametrize(
    "text,where",
    [
        ("<region> sample=a.wav lovel=loud", "kit.sfz:1: lovel=loud: expected an integer"),
        ("<group> pan=300\n<region> sample=a.wav", "kit.sfz:1: pan=300: expected a number"),
        ("<region> key=z9 sample=a.wav", "kit.sfz:1: key=z9: expected a MIDI note"),
        ("sample=a.wav", "kit.sfz:1: sample= before any header"),
        ("<region>\n<region> sample=a.wav", "kit.sfz:1: <region> without a sample"),
        ("\n<curve> curve_index=1", "kit.sfz:2: unknown header <curve>"),
        ("<region> sample=a.wav loop_mode=forever", "kit.sfz:1: loop_mode=forever: expected"),
    ],
)
def test_a_bad_value_names_the_file_and_line(text: str, where: str) -> None:
    with pytest.raises(SfzError, match=where):
        parse_sfz(text, Path("kit.sfz"))


def test_a_missing_or_unreadable_sample_names_the_sfz_line_and_the_sample(kit: Path) -> None:
    (kit.parent / "samples" / "snare b.flac").unlink()
    with pytest.raises(SfzError, match=r"kit\.sfz:8: sample .*snare b\.flac: cannot read it"):
        check_sfz(kit)
    (kit.parent / "samples" / "snare b.flac").write_bytes(b"not audio at all")
    with pytest.raises(SfzError, match=r"kit\.sfz:8: sample .*snare b\.flac: cannot read it"):
        check_sfz(kit)


def first_loud(x: np.ndarray, after: float) -> float:
    env = np.abs(x).max(axis=1)
    k = round(after * SR)
    return (k + int(np.argmax(env[k:] > 1e-6))) / SR


def spectrum_peak(x: np.ndarray) -> float:
    mono = x.mean(axis=1)
    spec = np.abs(np.fft.rfft(mono * np.hanning(mono.size)))
    return float(np.fft.rfftfreq(mono.size, 1 / SR)[np.argmax(spec)])


def test_layers_round_robin_and_attacks_on_the_onset(kit: Path) -> None:
    hits = [
        (0.1, "kick", 100),
        (0.6, "snare", 60),
        (0.9, "snare", 60),
        (1.2, "snare", 60),
        (1.5, "snare", 120),
    ]
    audio = render_sfz(onsets(hits), 2.0, kit, SR)
    assert np.abs(audio[: round(0.1 * SR)]).max() == 0.0
    assert first_loud(audio, 0.0) == pytest.approx(0.1, abs=2 / SR)
    peaks = [spectrum_peak(audio[round(t * SR) + 100 : round(t * SR) + 9000]) for t, *_ in hits]
    # kick 60 Hz; snare round robin a (200), b (300, a 44.1 kHz FLAC), a again; the loud layer
    assert peaks == pytest.approx([60, 200, 300, 200, 400], abs=8)
    quiet = np.abs(audio[round(0.6 * SR) : round(0.8 * SR)]).max()
    loud = np.abs(audio[round(1.5 * SR) : round(1.7 * SR)]).max()
    assert loud > 3 * quiet  # (120/127)² against (60/127)², and another layer


def test_a_closing_hihat_cuts_the_open_one_and_a_grab_cuts_a_cymbal(kit: Path) -> None:
    ring = render_sfz(onsets([(0.1, "hat_open", 100)]), 1.5, kit, SR)
    cut = render_sfz(onsets([(0.1, "hat_open", 100), (0.5, "hat_closed", 100)]), 1.5, kit, SR)
    after = slice(round(0.6 * SR), round(1.4 * SR))  # the closed hat (0.1 s) is over by then
    assert np.abs(ring[after]).max() > 0.1 and np.abs(cut[after]).max() < 1e-6
    fade = slice(round(0.5 * SR), round(0.52 * SR))  # ampeg_release 20 ms: no click
    open_only = cut[fade] - render_sfz(onsets([(0.5, "hat_closed", 100)]), 1.5, kit, SR)[fade]
    assert np.all(np.abs(np.diff(open_only[:, 0])) < 0.05)
    assert np.abs(open_only[-50:]).max() < 0.02


def test_render_with_an_sfz_kit_and_a_bad_kit_is_one_line(kit: Path, tmp_path: Path,
                                                         write_midi) -> None:  # type: ignore[no-untyped-def]  # fmt: skip
    import mido

    mid = write_midi(
        [
            mido.Message("note_on", channel=9, note=36, velocity=100, time=0),
            mido.Message("note_on", channel=9, note=38, velocity=100, time=240),
        ]
    )
    out = tmp_path / "out.mp4"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "render",
            str(mid),
            "-o",
            str(out),
            "--size",
            "160x90",
            "--fps",
            "10",
            "--aa",
            "0",
            "--tail",
            "0.3",
            "--map",
            "general-midi",
            "--sfz",
            str(kit),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0 and out.is_file(), run.stderr[-1500:]
    import av

    with av.open(str(out)) as c:
        audio = np.concatenate([f.to_ndarray().T for f in c.decode(audio=0)])
    assert np.abs(audio).max() > 0.05  # the SFZ kit sounds in the video
    (kit.parent / "samples" / "kick.wav").unlink()
    run = subprocess.run(
        [sys.executable, "-m", "services", "render", str(mid), "-o", str(out), "--sfz", str(kit)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert "kit.sfz:5: sample" in lines[0] and "kick.wav" in lines[0]


def test_a_grab_cuts_a_ringing_cymbal_sample(tmp_path: Path) -> None:
    from livedrummer.kit.loader import load_kit

    tone(tmp_path / "crash.wav", 700, 3.0)
    path = tmp_path / "crash.sfz"
    path.write_text("<region> key=49 sample=crash.wav\n")
    kit = load_kit("rock5")
    hits = onsets([(0.1, "kick", 110)])
    hits["note"], hits["instrument"] = 49, INSTRUMENTS.index("crash1")
    hits["zone"] = ZONES.index(Zone.BOW)
    chokes = [np.array([0.6]) if p.name == "crash1" else np.zeros(0) for p in kit.pieces]
    free = render_sfz(hits, 2.0, path, SR, kit)
    choked = render_sfz(hits, 2.0, path, SR, kit, chokes)
    g = round(0.6 * SR)
    np.testing.assert_allclose(choked[:g], free[:g], atol=1e-6)
    assert np.abs(free[g + 480 :]).max() > 0.1 and np.abs(choked[g + 480 :]).max() == 0.0


def test_the_live_sfz_mixer_is_the_offline_render_block_by_block(kit: Path) -> None:
    from livedrummer.audio.sfz_live import SfzLiveMixer

    hits = [
        (0.05, "hat_open", 80),
        (0.2, "kick", 90),
        (0.31, "snare", 70),
        (0.45, "hat_closed", 80),
        (0.6, "snare", 70),
        (0.7, "hat_open", 80),
        (0.9, "snare", 110),
        (1.0, "hat_closed", 60),
    ]
    on = onsets(hits)
    offline = render_sfz(on, 1.6, kit, SR)
    assert np.abs(offline).max() < 0.9  # not scaled for headroom: the twins must agree
    live = SfzLiveMixer(check_sfz(kit), None, SR)
    blocks, k = [], 0
    for size in [128, 300, 512, 77] * 80:
        while k < on.size and round(on["time_s"][k] * SR) < live.rendered + size + 1440:
            live.add(on[k], round(float(on["time_s"][k]) * SR))
            k += 1
        blocks.append(live.render(size))
    got = np.concatenate(blocks)[: len(offline)]
    assert k == on.size
    np.testing.assert_allclose(got[: round(1.5 * SR)], offline[: round(1.5 * SR)], atol=1e-5)
