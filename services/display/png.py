"""A minimal PNG writer for RGB or RGBA frames (``--frames-dir DIR``), with the standard zlib.

PNG is chunked: a signature, IHDR (size, 8-bit RGB or RGBA with straight alpha), one zlib
stream of filtered rows (filter type 0 on every row: the encoder does no prediction, which keeps
it fast and a little larger) and IEND, each chunk with its CRC. Limits: 8-bit only.
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
    """PNG bytes of an (H, W, 3) RGB or (H, W, 4) RGBA uint8 image, top row first."""
    h, w, channels = rgb.shape
    if channels not in (3, 4):
        raise ValueError(f"PNG of {channels} channels: want 3 (RGB) or 4 (RGBA)")
    rows = np.empty((h, 1 + channels * w), np.uint8)
    rows[:, 0] = 0
    rows[:, 1:] = rgb.reshape(h, channels * w)
    header = struct.pack(">IIBBBBB", w, h, 8, 2 if channels == 3 else 6, 0, 0, 0)
    return (
        _SIGNATURE
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
        + _chunk(b"IEND", b"")
    )


def write_png(path: Path | str, rgb: np.ndarray) -> None:
    Path(path).write_bytes(encode_png(rgb))
