"""Mutated Groove MIDI Dataset files: a named one-line error or a bounded, correct result.

Variants come from :func:`services.bench._fuzz.mutations` (truncated, bit-flipped, random runs,
huge and long delta times, zero tempo, a track longer than the file, 65,535 declared tracks)
for a seeded sample of the corpus, plus files built with absurd note counts. Each is read in
process with a generous time bound ("never hangs", not a speed figure: those are in
``livedrummer bench fuzz``); a few go through the real command line.
"""

from __future__ import annotations

import math
import random
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from livedrummer.errors import MidiFileError
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import MAX_DURATION_S, MAX_FILE_BYTES, read_midi_bytes
from livedrummer.timeline.performance import Performance
from services.bench._fuzz import Variant, absurd_note_file, mutations

REPO = Path(__file__).resolve().parents[3]
TD = load_note_map("roland-td")
SEED = 1150
BOUND_S = 5.0  # per file; typical is a few milliseconds
ABSURD_BOUND_S = 30.0  # 200,000 distinct note-ons: ~2 s alone, ~4 s on a loaded 2-core machine
NAME = "fuzzed.mid"
#: Where a named error points: a byte, a track, a tick, or the whole file's size or emptiness.
PLACE = re.compile(
    rf"^{re.escape(NAME)}: (byte \d+: |track \d+|tick \d+: |empty file$|\d+ bytes, |\d+ messages, "
    r"|no MTrk track chunk)"
)


@pytest.fixture(scope="module")
def sample(groove_files: list[Path]) -> list[Path]:
    return random.Random(SEED).sample(groove_files, 10)


def read_bounded(data: bytes, bound_s: float = BOUND_S) -> Performance | MidiFileError:
    """Read ``data``; return the result or the named error, checking time and message form."""
    start = time.perf_counter()
    try:
        perf: Performance | MidiFileError = read_midi_bytes(data, NAME, TD)
    except MidiFileError as exc:
        message = str(exc)
        assert "\n" not in message and PLACE.match(message), message
        perf = exc
    assert time.perf_counter() - start < bound_s
    return perf


def assert_bounded(perf: Performance, data: bytes) -> None:
    """What any result must satisfy, whatever the bytes were."""
    on = perf.onsets
    assert 0.0 <= perf.duration_s <= MAX_DURATION_S and math.isfinite(perf.duration_s)
    assert on.size <= len(data) // 2  # every note-on takes at least two bytes
    assert np.isfinite(on["time_s"]).all() and (np.diff(on["time_s"]) >= 0).all()
    assert (on["time_s"] >= 0).all() and (on["time_s"] <= perf.duration_s + 1e-9).all()
    assert ((on["note"] >= 0) & (on["note"] < 128)).all()
    assert ((on["velocity"] >= 1) & (on["velocity"] < 128)).all()


def test_mutated_corpus_files_end_in_named_errors_or_bounded_results(sample: list[Path]) -> None:
    rng = random.Random(SEED + 1)
    outcomes: dict[str, list[bool]] = {}
    for path in sample:
        original = read_midi_bytes(path.read_bytes(), NAME, TD)
        variants: list[Variant] = list(mutations(path.read_bytes(), rng, per_kind=3))
        for v in variants:
            got = read_bounded(v.data)
            outcomes.setdefault(v.kind, []).append(isinstance(got, MidiFileError))
            if isinstance(got, MidiFileError):
                continue
            assert_bounded(got, v.data)
            if v.kind == "many-tracks":  # the real track is read, nothing lost
                assert got.onsets.tobytes() == original.onsets.tobytes()
            if v.kind == "long-delta":  # everything shifted by 0x00FFFFFF ticks at 120 bpm
                shift = 0x00FFFFFF * 0.5 / original.tempo.ticks_per_beat
                assert got.onsets["note"].tolist() == original.onsets["note"].tolist()
                np.testing.assert_allclose(
                    got.onsets["time_s"] - shift, original.onsets["time_s"], atol=1e-6
                )
    errors = {kind: sum(flags) for kind, flags in outcomes.items()}
    total = {kind: len(flags) for kind, flags in outcomes.items()}
    # Structural damage is always caught; the rest is read correctly.
    for kind in ("truncated", "huge-delta", "zero-tempo", "track-too-long"):
        assert errors[kind] == total[kind] == 30, kind
    assert errors["many-tracks"] == errors["long-delta"] == 0
    assert 0 < errors["bit-flipped"] <= total["bit-flipped"]


def test_huge_delta_names_track_and_tick(sample: list[Path]) -> None:
    v = next(
        v for v in mutations(sample[0].read_bytes(), random.Random(1)) if v.kind == "huge-delta"
    )
    got = read_bounded(v.data)
    assert isinstance(got, MidiFileError)
    assert re.search(r"track 1: tick 268435455: an event \d+\.\d h into the file", str(got))


def test_absurd_note_counts_are_bounded() -> None:
    # 200,000 note-ons at one tick: one onset, the rest counted as duplicates.
    got = read_bounded(absurd_note_file(200_000), ABSURD_BOUND_S)
    assert not isinstance(got, MidiFileError)
    assert got.onsets.size == 1 and got.stats.duplicates_removed == 199_999
    assert got.duration_s == 0.0
    # 200,000 note-ons one tick apart: all of them, at the right times.
    data = absurd_note_file(200_000, delta=1)
    got = read_bounded(data, ABSURD_BOUND_S)
    assert not isinstance(got, MidiFileError)
    assert got.onsets.size == 200_000 and got.stats.duplicates_removed == 0
    assert_bounded(got, data)
    assert got.onsets["time_s"][-1] == pytest.approx(199_999 * 0.5 / 480)
    # More than a file may hold: refused before parsing.
    big = absurd_note_file(MAX_FILE_BYTES // 3 + 1)
    assert len(big) > MAX_FILE_BYTES
    got = read_bounded(big)
    assert isinstance(got, MidiFileError) and re.search(r"\d+ bytes, more than 4194304", str(got))


def test_random_bytes_after_a_valid_header_are_named_errors() -> None:
    rng = random.Random(SEED + 2)
    header = b"MThd\x00\x00\x00\x06\x00\x00\x00\x01\x01\xe0"
    for _ in range(200):
        body = rng.randbytes(rng.randint(0, 300))
        data = header + b"MTrk" + len(body).to_bytes(4, "big") + body
        got = read_bounded(data)
        if not isinstance(got, MidiFileError):
            assert_bounded(got, data)


def test_cli_reports_bad_files_in_one_line(sample: list[Path], tmp_path: Path) -> None:
    rng = random.Random(SEED + 3)
    variants = {v.kind: v for v in mutations(sample[1].read_bytes(), rng)}
    cases = {
        kind: variants[kind].data
        for kind in ("truncated", "huge-delta", "zero-tempo", "track-too-long")
    }
    cases["too-big"] = absurd_note_file(MAX_FILE_BYTES // 3 + 1)
    for kind, data in cases.items():
        path = tmp_path / f"{kind}.mid"
        path.write_bytes(data)
        proc = subprocess.run(
            [
                str(REPO / ".venv" / "bin" / "livedrummer"),
                "inspect",
                str(path),
                "--map",
                "roland-td",
            ],
            capture_output=True,
            text=True,
            timeout=60,
            cwd=REPO,
        )
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == 2, (kind, proc.stderr)
        assert len(lines) == 1 and "Traceback" not in proc.stderr, (kind, proc.stderr)
        assert lines[0].startswith("livedrummer: error: ") and str(path) in lines[0], lines[0]
        assert proc.stdout == ""
