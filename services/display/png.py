"""A minimal PNG writer for RGB frames (``--frames-dir DIR``), with zlib from the standard library.

PNG is chunked: a signature, IHDR (size, 8-bit RGB), one zlib stream of filtered rows (filter
type 0 on every row: the encoder does no prediction, which keeps it fast and a little larger)
and IEND, each chunk with its CRC. Limits: RGB 8-bit only.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def encode_png(rgb: np.ndarray, level: int = 3) -> bytes:
    """PNG bytes of an (H, W, 3) uint8 image, top row first."""
    h, w, _ = rgb.shape
    rows = np.empty((h, 1 + 3 * w), np.uint8)
    rows[:, 0] = 0
    rows[:, 1:] = rgb.reshape(h, 3 * w)
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return (
        _SIGNATURE
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
        + _chunk(b"IEND", b"")
    )


def write_png(path: Path | str, rgb: np.ndarray) -> None:
    Path(path).write_bytes(encode_png(rgb))
