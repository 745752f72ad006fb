"""Fuzz benchmark: noise through the serial parser, mutated corpus files through the reader.

Prints the figures of docs/benchmarks/reliability.md, all from one seed:

* serial: bytes of noise with valid messages in it (:func:`bench._fuzz.noisy_serial_stream`)
  fed to :class:`~livedrummer.midi.stream.MidiStreamParser` in random chunks; the parse rate,
  how many inserted messages came out intact (all of them, or it says so), garbage counted;
* files: ``--files`` Groove MIDI Dataset files, ``--variants`` of each mutation kind
  (:func:`bench._fuzz.mutations`) plus absurd note counts, each read by
  :func:`~livedrummer.midi.smf.read_midi_bytes`; how many ended in a named error and how many
  in a result, per kind, anything else raised (must be 0), and the median and maximum time.

Nothing here asserts: ``tests/services/input/test_fuzz_serial.py`` and
``tests/livedrummer/midi/test_fuzz_midifile.py`` do.
"""

from __future__ import annotations

import argparse
import itertools
import logging
import random
import statistics
import time
from collections import Counter
from pathlib import Path

from livedrummer.errors import MidiFileError
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_bytes
from livedrummer.midi.stream import MidiMessage, MidiStreamParser

from ._fuzz import Variant, absurd_note_file, mutations, noisy_serial_stream
from ._paths import DEFAULT_CORPUS
from ._paths import corpus as find_corpus


def serial(size: int, seed: int) -> None:
    rng = random.Random(seed)
    stream = noisy_serial_stream(rng, size)
    parser = MidiStreamParser()
    out: list[MidiMessage] = []
    data = stream.data
    cuts = [0]
    while cuts[-1] < len(data):
        cuts.append(cuts[-1] + rng.randint(1, 4096))
    start = time.perf_counter()
    for a, b in itertools.pairwise(cuts):
        out.extend(parser.feed(data[a:b]))
    elapsed = time.perf_counter() - start
    got = {(m.offset, m.status, m.data) for m in out}
    intact = sum((m.offset, m.status, m.data) in got for m in stream.inserted)
    st = parser.stats
    print(f"serial: {len(data):,} bytes in {len(cuts) - 1:,} chunks, seed {seed}")
    print(f"  parse rate         {len(data) / elapsed / 1e6:.2f} MB/s ({elapsed:.2f} s)")
    print(
        f"  inserted messages  {intact:,} of {len(stream.inserted):,} recovered intact "
        f"({stream.realtime_inside:,} real-time bytes inside them)"
    )
    print(f"  messages out       {st.messages:,} (the rest made by the noise)")
    print(f"  garbage counted    {st.garbage_bytes:,} of {stream.garbage_bytes:,} noise bytes")
    print(f"  SysEx              {st.sysex_truncated:,} truncated, {st.sysex_too_long:,} too long")


def files(corpus: Path, count: int, variants: int, seed: int, map_name: str) -> int:
    paths = sorted(find_corpus(corpus).rglob("*.mid"))
    rng = random.Random(seed)
    note_map = load_note_map(map_name)
    cases: list[Variant] = []
    for path in rng.sample(paths, min(count, len(paths))):
        cases.extend(mutations(path.read_bytes(), rng, per_kind=variants))
    cases.append(Variant("absurd-notes", "200,000 note-ons at one tick", absurd_note_file(200_000)))
    cases.append(
        Variant("absurd-notes", "200,000 note-ons 1 tick apart", absurd_note_file(200_000, delta=1))
    )
    errors: Counter[str] = Counter()
    results: Counter[str] = Counter()
    other: Counter[str] = Counter()
    times: list[float] = []
    slowest = ("", 0.0)
    for case in cases:
        start = time.perf_counter()
        try:
            read_midi_bytes(case.data, "fuzzed.mid", note_map)
            results[case.kind] += 1
        except MidiFileError:
            errors[case.kind] += 1
        except Exception as exc:  # counting what escapes is this benchmark's point
            other[f"{case.kind}: {type(exc).__name__}"] += 1
        elapsed = time.perf_counter() - start
        times.append(elapsed)
        if elapsed > slowest[1]:
            slowest = (f"{case.kind} ({case.detail})", elapsed)
    print(
        f"files: {len(cases):,} variants of {min(count, len(paths))} GMD files "
        f"({variants} per kind) + 2 absurd note counts, seed {seed}"
    )
    print(f"  {'kind':<16}{'named error':>12}{'result':>8}")
    for kind in dict.fromkeys(c.kind for c in cases):
        print(f"  {kind:<16}{errors[kind]:>12,}{results[kind]:>8,}")
    print(f"  total            {sum(errors.values()):>10,}{sum(results.values()):>8,}")
    print(f"  anything else    {sum(other.values())}" + (f"  {dict(other)}" if other else ""))
    print(
        f"  time per file    median {statistics.median(times) * 1e3:.2f} ms, "
        f"max {slowest[1] * 1e3:.0f} ms: {slowest[0]}"
    )
    return 1 if other else 0


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="livedrummer bench fuzz")
    parser.add_argument("--bytes", type=int, default=1_000_000, help="serial noise to parse")
    parser.add_argument("--files", type=int, default=100, help="GMD files to mutate")
    parser.add_argument("--variants", type=int, default=3, help="variants per mutation kind")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--corpus", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--map", default="roland-td")
    args = parser.parse_args(argv)
    serial(args.bytes, args.seed)
    logging.disable(logging.WARNING)  # the readers' warnings on each mutated file are counted
    try:
        return files(args.corpus, args.files, args.variants, args.seed, args.map)
    finally:
        logging.disable(logging.NOTSET)
