"""A tiny SoundFont 2 writer for tests: one drum preset (bank 128, preset 0), one sample.

The file follows the SoundFont 2.01 layout: ``RIFF sfbk`` holding ``LIST INFO`` (ifil, isng,
INAM), ``LIST sdta`` (smpl: 16-bit mono PCM, each sample followed by 46 zero points) and
``LIST pdta`` (phdr, pbag, pmod, pgen, inst, ibag, imod, igen, shdr, each ending with its
terminal record). The preset's one zone points at one instrument whose one zone covers keys
35..81 with the sample at ``root_key`` (overridingRootKey), so every GM drum note plays the
sample, transposed by its distance from the root.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

GEN_KEY_RANGE, GEN_INSTRUMENT, GEN_SAMPLE_ID, GEN_SAMPLE_MODES, GEN_ROOT_KEY = 43, 41, 53, 54, 58
GEN_RELEASE_VOL_ENV = 38  # timecents: 1200 * log2(seconds)


def tone(freq_hz: float = 440.0, seconds: float = 0.2, sr: int = 48_000) -> np.ndarray:
    """A cosine burst starting at full amplitude (a sharp attack), decaying, as int16."""
    t = np.arange(round(seconds * sr)) / sr
    wave = 0.8 * np.cos(2 * np.pi * freq_hz * t) * np.exp(-t / 0.08)
    return np.round(wave * 32767).astype("<i2")


def _chunk(tag: bytes, body: bytes) -> bytes:
    pad = b"\0" if len(body) % 2 else b""
    return tag + struct.pack("<I", len(body)) + body + pad


def _list(kind: bytes, *chunks: bytes) -> bytes:
    return _chunk(b"LIST", kind + b"".join(chunks))


def _zstr(text: str) -> bytes:
    raw = text.encode("ascii") + b"\0"
    return raw + (b"\0" if len(raw) % 2 else b"")


def _name(text: str) -> bytes:
    return text.encode("ascii")[:19].ljust(20, b"\0")


def sf2_bytes(
    sample: np.ndarray,
    sr: int = 48_000,
    root_key: int = 60,
    bank: int = 128,
    release_s: float | None = None,
) -> bytes:
    """The whole file: ``sample`` (int16) played by every key 35..81 of the preset at ``bank``
    (128: the GM drum kit), preset 0; ``release_s``: the volume envelope's release (SoundFont
    default: 1 ms), so a voice may ring on after its note-off as a cymbal's does."""
    n = int(sample.size)
    info = _list(
        b"INFO",
        _chunk(b"ifil", struct.pack("<HH", 2, 1)),
        _chunk(b"isng", _zstr("EMU8000")),
        _chunk(b"INAM", _zstr("livedrummer test kit")),
    )
    smpl = sample.astype("<i2").tobytes() + b"\0\0" * 46
    sdta = _list(b"sdta", _chunk(b"smpl", smpl))
    phdr = struct.pack("<20sHHHIII", _name("Test Drums"), 0, bank, 0, 0, 0, 0)
    phdr += struct.pack("<20sHHHIII", _name("EOP"), 0, 0, 1, 0, 0, 0)
    pbag = struct.pack("<HH", 0, 0) + struct.pack("<HH", 1, 0)
    pmod = b"\0" * 10
    pgen = struct.pack("<Hh", GEN_INSTRUMENT, 0) + b"\0" * 4
    inst = struct.pack("<20sH", _name("Tone"), 0) + struct.pack("<20sH", _name("EOI"), 1)
    release = [] if release_s is None else [round(1200 * np.log2(release_s))]
    igens = [
        struct.pack("<HBB", GEN_KEY_RANGE, 35, 81),  # must come first
        struct.pack("<Hh", GEN_ROOT_KEY, root_key),
        struct.pack("<Hh", GEN_SAMPLE_MODES, 0),  # no loop: a one-shot
        *(struct.pack("<Hh", GEN_RELEASE_VOL_ENV, tc) for tc in release),
        struct.pack("<Hh", GEN_SAMPLE_ID, 0),  # must come last
    ]
    ibag = struct.pack("<HH", 0, 0) + struct.pack("<HH", len(igens), 0)
    imod = b"\0" * 10
    igen = b"".join(igens) + b"\0" * 4
    shdr = struct.pack("<20sIIIIIBbHH", _name("tone"), 0, n, 8, n - 8, sr, root_key, 0, 0, 1)
    shdr += struct.pack("<20sIIIIIBbHH", _name("EOS"), 0, 0, 0, 0, 0, 0, 0, 0, 0)
    pdta = _list(
        b"pdta",
        _chunk(b"phdr", phdr),
        _chunk(b"pbag", pbag),
        _chunk(b"pmod", pmod),
        _chunk(b"pgen", pgen),
        _chunk(b"inst", inst),
        _chunk(b"ibag", ibag),
        _chunk(b"imod", imod),
        _chunk(b"igen", igen),
        _chunk(b"shdr", shdr),
    )
    return _chunk(b"RIFF", b"sfbk" + info + sdta + pdta)


def write_sf2(
    path: Path,
    sample: np.ndarray | None = None,
    root_key: int = 60,
    bank: int = 128,
    release_s: float | None = None,
) -> Path:
    """Write :func:`sf2_bytes` of ``sample`` (default :func:`tone`) to ``path``."""
    sample = tone() if sample is None else sample
    path.write_bytes(sf2_bytes(sample, root_key=root_key, bank=bank, release_s=release_s))
    return path
