"""Every drum file people have: the drum channel, lenient reading, no silent skips, doubled notes.

Each case writes its own file with mido (a full-band song, a piano piece, trailing bytes, a
2-byte time signature, running status after SysEx, an RMID wrapper, a GM2 file, a folder of
mixed extensions with one broken file, two tracks doubling a note) and checks what livedrummer
reads against a count made independently from mido's own reading of the sound version of the
file. The command-line cases run the real CLI in a subprocess.
"""

from __future__ import annotations

import io
import json
import math
import struct
import subprocess
import sys
from collections import Counter
from pathlib import Path

import mido
import pytest

from livedrummer.errors import MidiFileError
from livedrummer.midi.channels import channel_list, choose_drum_channels, parse_channel
from livedrummer.midi.notemap import bundled_note_maps, load_note_map
from livedrummer.midi.smf import read_midi_bytes, read_midi_file

REPO = Path(__file__).resolve().parents[3]
GM = load_note_map("general-midi")
TD = load_note_map("roland-td")


def note(n: int, t: int = 0, ch: int = 9, vel: int = 100) -> list[mido.Message]:
    """A note-on and its note-off ten ticks later (``t``: delta before the note-on)."""
    return [
        mido.Message("note_on", channel=ch, note=n, velocity=vel, time=t),
        mido.Message("note_on", channel=ch, note=n, velocity=0, time=10),
    ]


def save(path: Path, *tracks: list[mido.Message], midi_type: int = 1) -> Path:
    mid = mido.MidiFile(type=midi_type, ticks_per_beat=480)
    for messages in tracks:
        mid.tracks.append(mido.MidiTrack(messages))
    mid.save(path)
    return path


def mido_count(path: Path, channels: set[int] | None = None) -> tuple[Counter[int], Counter[int]]:
    """Independent count: note-ons (velocity > 0) per note on ``channels`` (None: all), and
    per channel on the others, as mido reads the file."""
    drums: Counter[int] = Counter()
    others: Counter[int] = Counter()
    for track in mido.MidiFile(path).tracks:
        for msg in track:
            if msg.type == "note_on" and msg.velocity > 0:
                if channels is None or msg.channel in channels:
                    drums[msg.note] += 1
                else:
                    others[msg.channel] += 1
    return drums, others


def band_song(path: Path) -> Path:
    """Piano (ch 1), bass (ch 2) and drums (ch 10) on three tracks, 2 bars."""
    piano = [mido.Message("program_change", channel=0, program=0)]
    bass = [mido.Message("program_change", channel=1, program=33)]
    drums = [mido.Message("program_change", channel=9, program=0)]
    for beat in range(8):
        piano += note(60 + beat % 5, 0 if beat == 0 else 470, ch=0)
        bass += note(36 + beat % 2, 0 if beat == 0 else 470, ch=1)  # in the kick's range
        drums += note(36 if beat % 2 == 0 else 38, 0 if beat == 0 else 470)
        drums += note(42, -10 + 10)  # hi-hat with each kick/snare
    return save(path, [mido.MetaMessage("set_tempo", tempo=500_000)], piano, bass, drums)


def cli(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "services", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


# ---- 1. the drum channel ----------------------------------------------------------------------


def test_full_band_song_reads_only_channel_10(tmp_path: Path) -> None:
    path = band_song(tmp_path / "band.mid")
    drums, others = mido_count(path, {9})
    perf = read_midi_file(path, GM)
    assert perf.stats.note_ons == drums
    assert perf.stats.other_channel_notes == others == Counter({0: 8, 1: 8})
    assert perf.onsets.size == sum(drums.values()) == 16
    assert set(perf.onsets["channel"].tolist()) == {9}
    assert perf.notices == ("16 notes on channels 1, 2 ignored; --channel all to use them",)
    everything = read_midi_file(path, GM, channel="all")
    assert everything.stats.note_ons == mido_count(path)[0]
    only_bass = read_midi_file(path, GM, channel=1)
    assert only_bass.stats.note_ons == mido_count(path, {1})[0]
    assert only_bass.notices == (
        "24 notes on channels 1, 10 ignored (--channel 2; --channel all reads them)",
    )


def test_inspect_reports_only_the_drums_and_one_line_on_the_other_channels(tmp_path: Path) -> None:
    path = band_song(tmp_path / "band.mid")
    proc = cli("inspect", str(path))
    assert proc.returncode == 0, proc.stderr
    assert "  note      16 notes on channels 1, 2 ignored; --channel all to use them" in (
        proc.stdout.splitlines()
    )
    assert "kick            4" in proc.stdout and "snare           4" in proc.stdout
    out = json.loads(cli("inspect", str(path), "--json").stdout)
    assert out["channels"] == [10] and out["other_channel_notes"] == {"1": 8, "2": 8}
    assert out["onsets"] == 16 and out["warnings"] == []
    every = json.loads(cli("inspect", str(path), "--json", "--channel", "all").stdout)
    # the bass's first note doubles the first kick (note 36, same instant): one hit
    assert every["channels"] is None and every["duplicates_removed"] == 1
    assert every["onsets"] == sum(mido_count(path)[0].values()) - 1
    bad = cli("inspect", str(path), "--channel", "17")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--channel" in bad.stderr


def test_one_melodic_channel_is_no_drum_part_and_one_plain_channel_is_drums(
    tmp_path: Path,
) -> None:
    piano = [mido.Message("program_change", channel=0, program=0)]
    for i in range(12):
        piano += note(60 + i, 0 if i == 0 else 100, ch=0)
    path = save(tmp_path / "piano.mid", piano, midi_type=0)
    perf = read_midi_file(path, GM)
    assert perf.onsets.size == 0 and perf.stats.other_channel_notes == Counter({0: 12})
    assert perf.notices[0].startswith("no drum part: all 12 notes are on channel 1, which plays")
    plain = [m for i in range(6) for m in note(38, 0 if i == 0 else 100, ch=2)]
    path = save(tmp_path / "plain.mid", plain, midi_type=0)
    perf = read_midi_file(path, GM)
    assert perf.onsets.size == 6 and perf.stats.note_ons == mido_count(path)[0]
    assert "all 6 notes are on channel 3, not the drum channel 10: read as drums" in perf.notices[0]


def test_channel_choice_rules() -> None:
    assert parse_channel("10") == 9 and parse_channel("ALL") == "all"
    with pytest.raises(ValueError, match="1-16"):
        parse_channel("0")
    assert channel_list([0, 1, 2, 3, 8, 10]) == "1-4, 9, 11"
    # a GM2/XG rhythm bank marks a second drum channel
    chosen = choose_drum_channels("auto", {9: 5, 10: 3, 0: 7}, {}, drum_banks=[10])
    assert chosen.channels == frozenset({9, 10})
    assert choose_drum_channels("auto", {0: 4, 1: 4}, {}).no_drum_part
    assert choose_drum_channels("auto", {0: 4}, {0: [116]}).channels == frozenset({0})  # Taiko


def test_file_with_no_drum_notes_says_so_and_writes_nothing(tmp_path: Path) -> None:
    tempo_only = [
        mido.MetaMessage("set_tempo", tempo=500_000),
        mido.MetaMessage("end_of_track", time=480 * 40),
    ]
    path = save(tmp_path / "empty.mid", tempo_only)
    out = tmp_path / "empty.bvh"
    proc = cli("export", str(path), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == [
        f"livedrummer: {path}: no drum notes: nothing for the drummer to play"
    ]
    assert not out.exists()


# ---- 2. lenient reading -----------------------------------------------------------------------


def drum_file(tmp_path: Path, name: str = "d.mid") -> Path:
    messages = [
        mido.MetaMessage("set_tempo", tempo=500_000),
        mido.MetaMessage("time_signature", numerator=4, denominator=4),
    ]
    for i in range(16):
        messages += note((36, 42, 38, 42)[i % 4], 0 if i == 0 else 230)
    return save(tmp_path / name, messages)


def same_reading(data: bytes, clean: Path, name: str = "x.mid") -> tuple[str, ...]:
    """Read ``data``; its onsets must be the clean file's and mido's count; its warnings."""
    perf = read_midi_bytes(data, name, GM)
    reference = read_midi_file(clean, GM)
    assert perf.onsets.tobytes() == reference.onsets.tobytes()
    assert perf.stats.note_ons == mido_count(clean)[0]
    return perf.warnings


def test_trailing_bytes_after_the_tracks_are_a_warning(tmp_path: Path) -> None:
    clean = drum_file(tmp_path)
    data = clean.read_bytes()
    (warning,) = same_reading(data + b"\n\n", clean)
    assert warning == (
        f"byte {len(data)}: 2 stray bytes where a chunk header should start: "
        "the 2 bytes after the last declared track are ignored"
    )
    junk = bytes(range(256)) * 12
    (warning,) = same_reading(data + junk, clean)
    assert warning.startswith(f"byte {len(data)}: corrupt chunk id")
    assert f"the {len(junk)} bytes after the last declared track are ignored" in warning
    # a track cut short before the declared tracks are all there is still an error
    short = bytearray(data)
    short[10:12] = (2).to_bytes(2, "big")
    cut = bytes(short) + data[14:40]
    with pytest.raises(MidiFileError, match=rf"x.mid: byte {len(data)}: truncated: track 2"):
        read_midi_bytes(cut, "x.mid", GM)


def test_track_count_mismatch_is_a_warning(tmp_path: Path) -> None:
    clean = drum_file(tmp_path)
    data = bytearray(clean.read_bytes())
    data[10:12] = (3).to_bytes(2, "big")
    assert same_reading(bytes(data), clean) == (
        "byte 10: header declares 3 tracks, file holds 1: all 1 are read",
    )


def test_two_byte_time_signature_is_read_past(tmp_path: Path) -> None:
    clean = drum_file(tmp_path)
    data = clean.read_bytes()
    good = b"\xff\x58\x04\x04\x02\x18\x08"
    at = data.index(good)
    bad = data[:at] + b"\xff\x58\x02\x04\x02" + data[at + len(good) :]
    bad = _fix_track_length(bad, -2)
    with pytest.raises(IndexError):  # mido itself refuses it
        mido.MidiFile(file=io.BytesIO(bad))
    (warning,) = same_reading(bad, clean)
    assert warning == (
        f"track 1 (bytes 14-{len(bad)}): byte {at}: time signature meta event "
        "of 2 bytes (expected 4) read as text"
    )


def _fix_track_length(data: bytes, change: int) -> bytes:
    """``data`` (one track) with the track chunk's length changed by ``change``."""
    (length,) = struct.unpack(">I", data[18:22])
    return data[:18] + struct.pack(">I", length + change) + data[22:]


def _varlen(value: int) -> bytes:
    out = [value & 0x7F]
    while value := value >> 7:
        out.append(0x80 | (value & 0x7F))
    return bytes(reversed(out))


def test_running_status_after_sysex_is_read(tmp_path: Path) -> None:
    # What rhythm-game charts do: note-ons in running status with a SysEx between them.
    events = [(0, 36), (120, 38), (120, 42), (120, 38)]
    body = bytearray()
    clean = []
    for i, (delta, n) in enumerate(events):
        if i == 0:
            body += _varlen(delta) + bytes((0x99, n, 100))
        else:
            body += _varlen(delta) + bytes((n, 100))
        body += b"\x00\xf0\x05\x43\x10\x4c\x00\xf7"  # a SysEx after every note
        clean += [*note(n, delta)[:1], mido.Message("sysex", data=[0x43, 0x10, 0x4C, 0x00])]
    body += b"\x00\xff\x2f\x00"
    data = b"MThd" + struct.pack(">IHHH", 6, 0, 1, 480) + b"MTrk"
    data += struct.pack(">I", len(body)) + bytes(body)
    reference = save(tmp_path / "clean.mid", clean, midi_type=0)
    warnings = same_reading(data, reference)
    assert warnings == (
        f"track 1 (bytes 14-{len(data)}): byte 35: running status after a SysEx event (3 times)",
    )


def test_rmid_wrapper_is_unwrapped(tmp_path: Path) -> None:
    clean = drum_file(tmp_path)
    smf = clean.read_bytes()
    pad = b"\x00" if len(smf) % 2 else b""
    chunks = b"data" + struct.pack("<I", len(smf)) + smf + pad
    riff = b"RIFF" + struct.pack("<I", 4 + len(chunks)) + b"RMID" + chunks
    assert same_reading(riff, clean, "song.rmi") == ()
    with pytest.raises(MidiFileError, match=r"song.rmi: byte 12: RIFF-RMID file without"):
        read_midi_bytes(b"RIFF\x04\x00\x00\x00RMID", "song.rmi", GM)


def test_unreadable_track_is_still_one_line_naming_the_byte(tmp_path: Path) -> None:
    body = b"\x00\xf0\x01\x00\x00\x99\xc8\x40\x00\xff\x2f\x00"  # running status, data byte 200
    data = b"MThd" + struct.pack(">IHHH", 6, 0, 1, 480) + b"MTrk"
    data += struct.pack(">I", len(body)) + body
    with pytest.raises(MidiFileError) as err:
        read_midi_bytes(data, "bad.mid", GM)
    assert str(err.value) == (
        f"bad.mid: track 1 (bytes 14-{len(data)}): byte 28: data byte 0xC8 is not in range 0..127"
    )


def test_inspect_json_counts_every_warning(tmp_path: Path) -> None:
    clean = drum_file(tmp_path)
    data = bytearray(clean.read_bytes())
    data[10:12] = (2).to_bytes(2, "big")
    path = tmp_path / "two.mid"
    path.write_bytes(bytes(data) + b"\r\n")
    out = json.loads(cli("inspect", str(path), "--json").stdout)
    assert len(out["warnings"]) == 2 and out["onsets"] == 16
    proc = cli("inspect", str(path))
    assert proc.stdout.count("  warning   ") == 2


# ---- 3. no silent skips -----------------------------------------------------------------------


def test_check_folder_reads_every_extension_and_goes_on_past_a_broken_file(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "songs"
    (folder / "sub").mkdir(parents=True)
    short = [m for i in range(4) for m in note((36, 38)[i % 2], 0 if i == 0 else 470)]
    for name in ("a.mid", "B.MID", "c.midi", "sub/d.kar"):
        save(folder / name, short)
    smf = (folder / "a.mid").read_bytes()
    (folder / "e.RMI").write_bytes(
        b"RIFF"
        + struct.pack("<I", 12 + len(smf))
        + b"RMID"
        + b"data"
        + struct.pack("<I", len(smf))
        + smf
    )
    (folder / "broken.mid").write_bytes(smf[:30])
    (folder / "notes.txt").write_text("not MIDI")
    proc = cli("check", str(folder), "--json", "--summary", "--fps", "60")
    assert proc.returncode == 2
    out = json.loads(proc.stdout)
    assert out["files"] == 5 and out["unreadable_files"] == 1
    assert out["notes"] == 5 * 4
    errors = [line for line in proc.stderr.splitlines() if "error" in line]
    assert errors == [
        f"livedrummer: error: {folder / 'broken.mid'}: byte 14: truncated: track 1 declares "
        f"{len(smf) - 22} bytes but the file ends 8 bytes after its header",
        "livedrummer: error: 1 of 6 files could not be read",
    ]


def test_every_file_command_prints_the_unknown_notes_line(tmp_path: Path) -> None:
    # note 0: no bundled map names it (the drum plugins' maps name nearly every other note)
    messages = [m for i in range(4) for m in note((36, 0)[i % 2], 0 if i == 0 else 470)]
    path = save(tmp_path / "odd.mid", messages)
    line = f"livedrummer: {path}: unknown notes: note 0 x2 (not in map general-midi; not played)"
    out = tmp_path / "odd.bvh"
    for args in (["sticking", str(path)], ["export", str(path), "-o", str(out), "--fps", "10"]):
        proc = cli(*args)
        assert proc.returncode == 0, proc.stderr
        assert line in proc.stderr.splitlines(), proc.stderr
    # render, display and check read through the same front door (services.cli.files)
    for module in ("render", "display", "check"):
        text = (REPO / "services" / "cli" / f"{module}.py").read_text()
        assert "read_performance(args" in text and "read_midi_file" not in text


def test_export_spans_the_file_plus_the_tail_as_render_does(tmp_path: Path) -> None:
    from services.display.export import frame_count

    messages = [m for i in range(4) for m in note(38, 0 if i == 0 else 470)]
    messages.append(mido.MetaMessage("end_of_track", time=480 * 8))  # 4 s of silence at the end
    path = save(tmp_path / "tail.mid", [mido.MetaMessage("set_tempo", tempo=500_000)], messages)
    duration = read_midi_file(path, GM).duration_s
    out = tmp_path / "tail.bvh"
    proc = cli("export", str(path), "-o", str(out), "--fps", "30")
    assert proc.returncode == 0, proc.stderr
    frames = int(
        next(x for x in out.read_text().splitlines() if x.startswith("Frames:")).split()[1]
    )
    assert frames == frame_count(duration + 1.0, 30) == math.ceil((duration + 1.0) * 30)


# ---- 4. GM2 notes and the auto map ------------------------------------------------------------


def test_gm2_notes_are_known_ignored_ones_reported(tmp_path: Path) -> None:
    notes = [27, 31, 33, 33, 34, 36, 38, 82, 85, 87]
    messages = [m for i, n in enumerate(notes) for m in note(n, 0 if i == 0 else 200)]
    path = save(tmp_path / "gm2.mid", messages)
    drums, _ = mido_count(path)
    perf = read_midi_file(path, bundled_note_maps())
    assert perf.map_name == "general-midi"
    assert perf.stats.unknown_notes == Counter()
    assert perf.stats.ignored_notes == Counter({n: drums[n] for n in (27, 31, 33, 34)})
    assert perf.onsets.size == sum(drums[n] for n in (36, 38, 82, 85, 87))
    lines = perf.report_lines(GM.ignored)
    assert (
        "ignored notes: note 27 High Q x1, note 31 Sticks x1, note 33 Metronome click x2, "
        "note 34 Metronome bell x1 (no place on a drum kit; not played)"
    ) in lines
    assert lines[0].startswith("map auto: general-midi knows 10 of 10 drum notes")


def test_auto_map_picks_the_map_that_knows_most(tmp_path: Path) -> None:
    # Roland's hi-hat edge (22) and rim notes (40, 26) are unknown to General MIDI
    notes = [36, 22, 38, 26, 36, 40]
    messages = [m for i, n in enumerate(notes) for m in note(n, 0 if i == 0 else 200)]
    path = save(tmp_path / "td.mid", messages)
    perf = read_midi_file(path, bundled_note_maps())
    assert perf.map_name == "roland-td" and perf.stats.unknown_notes == Counter()
    assert perf.onsets.size == len(notes)


# ---- 5. doubled notes -------------------------------------------------------------------------


def test_a_note_doubled_on_two_tracks_is_one_hit_at_the_higher_velocity(tmp_path: Path) -> None:
    # 960 ticks per beat at 120 bpm: one tick is 0.52 ms, so 1 tick apart is within 1 ms and
    # 2 ticks apart is not.
    one = [*note(38, 0, vel=70), *note(42, 950, vel=90), *note(36, 950, vel=50)]
    two = [*note(38, 0, vel=110), *note(42, 951, vel=60), *note(36, 952, vel=127)]
    mid = mido.MidiFile(ticks_per_beat=960)
    for messages in ([mido.MetaMessage("set_tempo", tempo=500_000)], one, two):
        mid.tracks.append(mido.MidiTrack(messages))
    path = tmp_path / "doubled.mid"
    mid.save(path)
    drums, _ = mido_count(path)
    perf = read_midi_file(path, GM)
    assert perf.stats.note_ons == drums and sum(drums.values()) == 6
    assert perf.onsets["note"].tolist() == [38, 42, 36, 36]
    assert perf.onsets["velocity"].tolist() == [110, 90, 50, 127]
    assert perf.stats.duplicates_removed == 2 and perf.summary()["duplicates_removed"] == 2


# ---- 4. rhythm-game charts --------------------------------------------------------------------


def chart_file(path: Path) -> Path:
    """A chart: guitar and drums on channel 1, drums with Expert and Hard gems, animation notes
    and a yellow tom marker over beats 4-7."""
    guitar = [mido.MetaMessage("track_name", name="PART GUITAR")]
    drums = [mido.MetaMessage("track_name", name="PART DRUMS")]
    for beat in range(12):
        guitar += note(96 + beat % 5, 0 if beat == 0 else 470, ch=0)
    tick = 0
    events: list[tuple[int, mido.Message]] = []
    for beat in range(12):
        at = beat * 480
        gems = [96 if beat % 2 == 0 else 97, 98] + ([100] if beat == 0 else [])
        for gem in gems:
            events.append((at, mido.Message("note_on", note=gem, velocity=100)))
            events.append((at + 10, mido.Message("note_on", note=gem, velocity=0)))
        events.append((at, mido.Message("note_on", note=86, velocity=90)))  # Hard yellow
        events.append((at, mido.Message("note_on", note=24 + beat, velocity=90)))  # animation
    events.append((4 * 480, mido.Message("note_on", note=110, velocity=100)))
    events.append((8 * 480, mido.Message("note_off", note=110, velocity=0)))  # ends before 8
    for at, msg in sorted(events, key=lambda e: e[0]):
        drums.append(msg.copy(time=at - tick))
        tick = at
    return save(path, [mido.MetaMessage("set_tempo", tempo=500_000)], guitar, drums)


def test_a_chart_plays_its_expert_drums_with_tom_markers(tmp_path: Path) -> None:
    path = chart_file(tmp_path / "notes.mid")
    # Independent count from mido: Expert gems of PART DRUMS, yellow gems under the marker.
    mid = mido.MidiFile(path)
    part = next(t for t in mid.tracks if t.name == "PART DRUMS")
    tick, start, end = 0, -1, -1
    gems: Counter[int] = Counter()
    yellow_ticks = []
    for msg in part:
        tick += msg.time
        if msg.type == "note_on" and msg.velocity and 95 <= msg.note <= 100:
            gems[msg.note] += 1
            if msg.note == 98:
                yellow_ticks.append(tick)
        if msg.type == "note_on" and msg.note == 110:
            start = tick
        if msg.type == "note_off" and msg.note == 110:
            end = tick
    toms = sum(start <= t < end for t in yellow_ticks)
    perf = read_midi_file(path, bundled_note_maps())
    assert perf.map_name == "rock-band-chart"
    by_piece: dict[str, dict[str, int]] = perf.summary()["by_piece"]
    counts = {k: sum(v.values()) for k, v in by_piece.items()}
    assert counts == {
        "kick": gems[96],
        "snare": gems[97],
        "hihat": gems[98] - toms,
        "tom1": toms,
        "crash1": gems[100],
    }
    assert toms == 4
    assert perf.stats.unknown_notes == Counter()
    assert sum(perf.stats.ignored_notes.values()) == 24  # Hard gems and animation notes
    assert perf.notices == (
        "rhythm-game chart: track 'PART DRUMS' read, Expert gems played, "
        "1 tom markers applied; 12 notes on its other tracks ignored",
    )


# ---- 4. the percussion extension --------------------------------------------------------------


def test_percussion_extension_plays_gm_percussion_notes(tmp_path: Path) -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.sticking.result import NOT_PLAYED
    from livedrummer.sticking.strategy import stick_performance

    notes = [36, 54, 38, 56, 36, 76, 38, 63]  # kick, tambourine, snare, cowbell, woodblock, conga
    messages = [m for i, n in enumerate(notes) for m in note(n, 0 if i == 0 else 230)]
    path = save(tmp_path / "perc.mid", messages)
    perf = read_midi_file(path, GM)
    assert perf.onsets.size == len(notes)
    plain = stick_performance(perf, load_kit("rock5"), "optimal")
    extended = stick_performance(perf, load_kit("rock5+percussion"), "optimal")
    percussion = [i for i, n in enumerate(notes) if n not in (36, 38)]
    assert all(plain.limb[i] == NOT_PLAYED for i in percussion)
    assert all(extended.limb[i] != NOT_PLAYED for i in range(len(notes)))
    kit = load_kit("rock5-left+percussion")  # mirrored with its kit
    assert (
        kit.piece("cowbell").position_m[0]
        == -load_kit("rock5+percussion").piece("cowbell").position_m[0]
    )
    proc = cli("check", str(path), "--kit", "rock5+percussion", "--json", "--summary")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["notes"] == len(notes) and out["not_played"] == 0
    assert out["contact_error_mm"]["max"] < 5.0


def test_check_of_an_unreadable_file_gives_its_error_and_no_figures(tmp_path: Path) -> None:
    broken = tmp_path / "broken.mid"
    broken.write_bytes(b"MThd\x00\x00\x00\x06\x00\x01\x00\x01\x01\xe0MTrk\x00\x00\x01\x00")
    proc = cli("check", str(broken), "--json", "--summary", "--fps", "60")
    assert proc.returncode == 2
    out = json.loads(proc.stdout)
    assert out["files"] == 0 and out["unreadable_files"] == 1
    assert out["contact_error_mm"] is None and out["penetration_mm"] is None
    assert out["joint_limit_violations"] is None
    (failed,) = out["unreadable"]
    assert failed["file"] == str(broken) and "truncated" in failed["error"]
    assert f"livedrummer: error: {failed['error']}" in proc.stderr.splitlines()
    text = cli("check", str(broken), "--fps", "60")
    assert text.returncode == 2 and "within 5 mm" not in text.stdout
    assert "no figures" in text.stdout


def test_the_not_played_count_names_the_kit_that_plays_the_percussion(tmp_path: Path) -> None:
    from livedrummer.kit.loader import kit_that_plays, load_kit

    notes = [36, 54, 38, 56, 36, 76, 38, 56]  # kick, tambourine, snare, cowbell, conga, cowbell
    path = save(
        tmp_path / "perc.mid",
        [m for i, n in enumerate(notes) for m in note(n, 0 if i == 0 else 230)],
    )
    proc = cli("check", str(path), "--fps", "30")
    assert proc.returncode == 0, proc.stderr
    (line,) = [ln for ln in proc.stdout.splitlines() if "not played" in ln]
    assert line.endswith(
        "(not played: 4; cowbell x2, tambourine x1, percussion x1 have no piece "
        "on rock5: --kit rock5+percussion plays them)"
    )
    out = json.loads(cli("check", str(path), "--fps", "30", "--json", "--summary").stdout)
    assert out["no_piece"] == {"cowbell": 2, "tambourine": 1, "percussion": 1}
    assert out["kit_that_plays_them"] == "rock5+percussion"
    extended = cli("check", str(path), "--fps", "30", "--kit", "rock5+percussion").stdout
    assert "(not played: 0)" in extended
    assert kit_that_plays(load_kit("rock5-left"), ["cowbell"]) == "rock5-left+percussion"
    assert kit_that_plays(load_kit("rock5+percussion"), ["cowbell"]) is None  # has it already
