"""Validation of row payloads (ONSET, CONTROL, STAGE_CUE), shared by encode and decode.

A fast whole-array path for the common case (every row valid); only when it fails are the
fields checked one by one, so the error names the first bad row and field.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.kit.vocabulary import HIHATS, INSTRUMENTS, ZONES
from livedrummer.protocol.spec import MAX_ROWS, Kind, fail
from livedrummer.timeline.events import ONSET_DTYPE, ControlKind


def _check_range(rows: np.ndarray, name: str, hi: int, lo: int = 0) -> None:
    col = rows[name]
    bad = (col < lo) | (col >= hi)
    if bad.any():
        i = int(np.argmax(bad))
        raise fail(f"row {i}.{name}", f"out of range {lo}..{hi - 1}", int(col[i]))


def _check_time(rows: np.ndarray) -> None:
    bad = ~np.isfinite(rows["time_s"])
    if bad.any():
        i = int(np.argmax(bad))
        raise fail(f"row {i}.time_s", "not finite", float(rows["time_s"][i]))


_ONSET_CODE_LIMITS = np.array(
    [128, 128, 16, len(INSTRUMENTS), len(ZONES), len(HIHATS)], np.uint8
)  # exclusive upper bounds of the u1 fields note … hihat (bytes 8..13 of a row)


def _onsets_ok(rows: np.ndarray) -> bool:
    """Fast path for the common case (all valid): a few whole-array operations."""
    raw = np.ascontiguousarray(rows).view(np.uint8).reshape(rows.size, ONSET_DTYPE.itemsize)
    codes = raw[:, 8:14]
    if (codes >= _ONSET_CODE_LIMITS).any() or not codes[:, 1].all():
        return False
    op = rows["openness"]
    with np.errstate(invalid="ignore"):
        in_range = (op >= 0) & (op <= 1)
    return bool(np.isfinite(rows["time_s"]).all() and (in_range | np.isnan(op)).all())


def check_onsets(rows: np.ndarray) -> None:
    if _onsets_ok(rows):
        return
    _check_time(rows)
    _check_range(rows, "note", 128)
    _check_range(rows, "velocity", 128, 1)
    _check_range(rows, "channel", 16)
    _check_range(rows, "instrument", len(INSTRUMENTS))
    _check_range(rows, "zone", len(ZONES))
    _check_range(rows, "hihat", len(HIHATS))
    op = rows["openness"]
    bad = ~np.isnan(op) & ~((op >= 0) & (op <= 1))
    if bad.any():
        i = int(np.argmax(bad))
        raise fail(f"row {i}.openness", "expected NaN or 0..1", float(op[i]))


def check_controls(rows: np.ndarray) -> None:
    _check_time(rows)
    _check_range(rows, "kind", len(ControlKind))
    _check_range(rows, "channel", 16)
    _check_range(rows, "number", 128)
    _check_range(rows, "value", 128)


def check_stage_cues(rows: np.ndarray) -> None:
    _check_time(rows)
    _check_range(rows, "camera", 9)
    _check_range(rows, "cut", 2)
    _check_range(rows, "blackout", 2, lo=-1)


ROW_CHECKS = {Kind.ONSET: check_onsets, Kind.CONTROL: check_controls,
              Kind.SHOWN_ONSET: check_onsets, Kind.SHOWN_CONTROL: check_controls,
              Kind.STAGE_CUE: check_stage_cues}  # fmt: skip


def rows_from(data: memoryview, dtype: np.dtype[Any], what: str) -> np.ndarray:
    size = len(data)
    if size == 0 or size % dtype.itemsize:
        raise fail(
            f"{what} payload", f"not a whole number (>= 1) of {dtype.itemsize}-byte rows", size
        )
    n = size // dtype.itemsize
    if n > MAX_ROWS:
        raise fail(f"{what} payload", f"more than {MAX_ROWS} rows", n)
    return np.frombuffer(data, dtype=dtype, count=n)
