"""MIDI files onto one timeline: tempo maps, grids, the decoder's rules, and bad files."""

from __future__ import annotations

import math
import random
from pathlib import Path

import mido
import numpy as np
import pytest
from conftest import MidiWriter

from livedrummer.errors import MidiFileError
from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES, HiHat
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_bytes, read_midi_file
from livedrummer.timeline.events import ControlKind

TD = load_note_map("roland-td")
GM = load_note_map("general-midi")
DEMO = Path(__file__).resolve().parents[3] / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"


def on(note: int, vel: int = 100, t: int = 0, ch: int = 9) -> mido.Message:
    return mido.Message("note_on", note=note, velocity=vel, time=t, channel=ch)


def meta(kind: str, t: int = 0, **kw: int) -> mido.MetaMessage:
    return mido.MetaMessage(kind, time=t, **kw)


def test_tempo_changes_become_seconds(write_midi: MidiWriter) -> None:
    # 120 bpm for one beat (0.5 s), then 60 bpm: the next beat lasts 1 s.
    path = write_midi(
        [
            meta("set_tempo", tempo=500_000),
            on(38),
            on(38, t=480),
            meta("set_tempo", tempo=1_000_000),
            on(38, t=480),
            on(38, t=240),
        ]
    )
    perf = read_midi_file(path, GM)
    assert perf.onsets["time_s"].tolist() == pytest.approx([0.0, 0.5, 1.5, 2.0])
    assert [round(b) for _, b in perf.tempo.bpm_changes()] == [120, 60]


def test_tracks_merge_in_time_order(write_midi: MidiWriter) -> None:
    path = write_midi([meta("set_tempo", tempo=500_000)], [on(36), on(36, t=960)], [on(42, t=480)])
    perf = read_midi_file(path, GM)
    assert perf.onsets["note"].tolist() == [36, 42, 36]
    assert perf.onsets["time_s"].tolist() == pytest.approx([0.0, 0.5, 1.0])


def test_grid_follows_time_signatures(write_midi: MidiWriter) -> None:
    # Two bars of 4/4, then 6/8 (eighth-note beats, six per bar).
    path = write_midi(
        [
            meta("time_signature", numerator=4, denominator=4),
            on(36),
            meta("time_signature", t=8 * 480, numerator=6, denominator=8),
            on(36, t=6 * 240),
        ]
    )
    grid = read_midi_file(path, GM).grid
    assert grid.beat_in_bar[:8].tolist() == [0, 1, 2, 3, 0, 1, 2, 3]
    assert grid.bar[:8].tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
    assert grid.beat_s[8] == pytest.approx(4.0)
    assert grid.beat_s[9] - grid.beat_s[8] == pytest.approx(0.25)  # an eighth at 120 bpm
    assert grid.bar[8] == 2 and grid.beat_in_bar[8] == 0 and grid.beat_in_bar[13] == 5
    assert grid.beat_position(np.array([0.75, 4.125])).tolist() == pytest.approx([1.5, 8.5])


def test_velocity_zero_is_note_off_and_doubles_are_removed(write_midi: MidiWriter) -> None:
    path = write_midi([on(38, 90), on(38, 90), on(38, 0, t=10), on(38, 91, t=0), on(40, 90)])
    perf = read_midi_file(path, GM)
    assert perf.onsets["velocity"].tolist() == [90, 91, 90]
    assert perf.stats.duplicates_removed == 1
    assert perf.stats.note_ons[38] == 3  # raw count keeps the double
    assert perf.stats.ignored["note_off"] == 1


def test_unknown_notes_are_counted_not_lost(write_midi: MidiWriter) -> None:
    path = write_midi([on(36), on(99, t=10), on(99, t=10), on(20, t=10)])
    summary = read_midi_file(path, GM).summary()
    assert summary["onsets"] == 1
    assert summary["unknown_notes"] == {"20": 1, "99": 2}
    assert summary["by_note"] == {"20": 1, "36": 1, "99": 2}


def test_hihat_openness_from_the_pedal_or_from_the_note(write_midi: MidiWriter) -> None:
    cc = mido.Message("control_change", control=4, value=45, channel=9)
    path = write_midi([on(46), on(38, t=10), cc.copy(time=10), on(42), on(44, t=10)])
    on_ = read_midi_file(path, TD).onsets
    hh = on_[on_["instrument"] == INSTRUMENTS.index("hihat")]
    # 46 before any CC4 → open by its note; 42 after CC4=45 → half open (TD closes at 90).
    assert hh["openness"].tolist() == pytest.approx([1.0, 0.5, 0.0])
    assert [HIHATS[h] for h in hh["hihat"]] == [HiHat.OPEN, HiHat.CLOSED, HiHat.PEDAL]
    assert math.isnan(on_["openness"][on_["note"] == 38][0])


def test_chokes_and_strike_position_are_control_events(write_midi: MidiWriter) -> None:
    grab = mido.Message("polytouch", note=49, value=127, channel=9)
    path = write_midi(
        [mido.Message("control_change", control=16, value=60, channel=9), on(49),
         grab.copy(time=100), grab.copy(value=0, time=100),
         mido.Message("polytouch", note=99, value=127, channel=9)]
    )  # fmt: skip
    perf = read_midi_file(path, TD)
    kinds = perf.controls["kind"].tolist()
    assert kinds == [ControlKind.STRIKE_POSITION, ControlKind.CHOKE, ControlKind.CHOKE]
    assert perf.controls["value"].tolist() == [60, 127, 0]
    assert perf.stats.ignored["polytouch on an unmapped note"] == 1
    assert ZONES[perf.onsets["zone"][0]].value == "bow"


def test_smpte_division(tmp_path: Path) -> None:
    # 25 fps x 40 ticks per frame = 1000 ticks per second.
    mid = mido.MidiFile()
    track = mido.MidiTrack([on(38), on(38, t=1500)])
    mid.tracks.append(track)
    path = tmp_path / "smpte.mid"
    mid.save(path)
    data = bytearray(path.read_bytes())
    data[12:14] = bytes([0x100 - 25, 40])
    perf = read_midi_bytes(bytes(data), "smpte.mid", GM)
    assert perf.onsets["time_s"].tolist() == pytest.approx([0.0, 1.5])


def test_zero_tempo_is_an_error(write_midi: MidiWriter) -> None:
    path = write_midi([meta("set_tempo", tempo=0), on(38)])
    with pytest.raises(MidiFileError, match=r"t.mid: tick 0: tempo 0"):
        read_midi_file(path, GM)


# ---- bad files: one line, naming the file and the place --------------------------------------


def _raises(data: bytes, pattern: str) -> str:
    with pytest.raises(MidiFileError, match=pattern) as err:
        read_midi_bytes(data, "bad.mid", TD)
    message = str(err.value)
    assert message.startswith("bad.mid: ") and "\n" not in message
    return message


def test_empty_and_foreign_files() -> None:
    _raises(b"", "empty file")
    _raises(b"RIFF\x00\x00\x00\x00WAVE", r"byte 0: not a Standard MIDI File")
    _raises(b"MThd\x00\x00", r"ends inside the 14-byte header")


def test_truncated_file_names_the_track_and_offset() -> None:
    data = DEMO.read_bytes()
    _raises(data[: len(data) // 2], r"byte 14: truncated: track 1 declares \d+ bytes")


def test_corrupt_chunk_is_an_error_and_stray_bytes_after_the_tracks_a_warning() -> None:
    data = DEMO.read_bytes()
    _raises(data[:14] + b"\x00\xff\x13\x37" + data[18:], r"byte 14: corrupt chunk id")
    perf = read_midi_bytes(data + b"\x01\x02\x03", "stray.mid", TD)
    assert perf.warnings == (
        f"byte {len(data)}: 3 stray bytes where a chunk header should start: the 3 bytes after "
        "the last declared track are ignored",
    )
    assert perf.onsets.tobytes() == read_midi_bytes(data, "ok.mid", TD).onsets.tobytes()


def test_bad_event_data_names_the_track() -> None:
    data = bytearray(DEMO.read_bytes())
    # Replace the track body with a note-on whose data bytes are out of range.
    body = b"\x00\x99\xff\xff" + b"\x00\xff\x2f\x00"
    data = data[:18] + len(body).to_bytes(4, "big") + body
    _raises(bytes(data), r"track 1 \(bytes 14-30\)")


def test_random_bytes_never_escape_as_other_exceptions() -> None:
    rng = random.Random(7)
    valid = DEMO.read_bytes()
    for _ in range(300):
        data = bytearray(valid)
        for _ in range(rng.randint(1, 20)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        try:
            read_midi_bytes(bytes(data), "flipped.mid", TD)
        except MidiFileError as exc:
            assert str(exc).startswith("flipped.mid: ")
    for _ in range(100):
        junk = bytes(rng.randrange(256) for _ in range(rng.randint(0, 400)))
        with pytest.raises(MidiFileError):
            read_midi_bytes(junk, "junk.mid", TD)


def test_directory_and_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MidiFileError, match="is a directory"):
        read_midi_file(tmp_path, TD)
    with pytest.raises(MidiFileError, match="cannot read"):
        read_midi_file(tmp_path / "nope.mid", TD)
