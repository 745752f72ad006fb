"""Where a frame differs from a cached still picture: pixel boxes and the tiles that cover them.

The renderer's static layer (``services/display/passes/layer.py``) caches the kit at rest and
redraws, each frame, the screen tiles where the frame can differ from it. :func:`box_rects`
gives the pixel box of a set of world points (a box's corners: a convex body's perspective image
lies in the box of its projected corners); :func:`tile_cover` turns the union of pixel boxes
into few non-overlapping rectangles of whole tiles, runs along each tile row stacked where
consecutive rows have the same run.

Pure numpy, no GPU, vectorised over boxes. Limits: a point behind the camera's eye plane gives
the whole frame (correct, no saving); axis-aligned boxes over-cover slanted parts.
"""

from __future__ import annotations

import numpy as np

#: tile side in pixels of the redrawn region
TILE_PX = 32

Rect = tuple[int, int, int, int]  # x, y (from the bottom, GL), width, height

_CORNERS = np.array([[i >> 2 & 1, i >> 1 & 1, i & 1] for i in range(8)], bool)


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The 8 corners (B, 8, 3) of each axis-aligned box from ``lo`` (B, 3) to ``hi`` (B, 3)."""
    lo, hi = np.atleast_2d(lo).astype(np.float64), np.atleast_2d(hi).astype(np.float64)
    return np.where(_CORNERS[None], hi[:, None, :], lo[:, None, :])


def box_rects(points: np.ndarray, view_proj: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Pixel boxes (B, 4: x0, y0, x1, y1, from the bottom left) of each set of world
    ``points`` (B, M, 3) under row-major ``view_proj``, clipped to the frame; a set with a
    point behind the eye plane gets the whole frame."""
    w, h = size
    if not len(points):
        return np.zeros((0, 4), np.int64)
    homo = np.concatenate([points, np.ones((*points.shape[:2], 1))], axis=2)
    clip = homo @ np.asarray(view_proj, np.float64).T
    behind = clip[..., 3].min(axis=1) <= 1e-4
    wdiv = np.where(clip[..., 3:4] > 1e-4, clip[..., 3:4], 1.0)
    px = (clip[..., :2] / wdiv * 0.5 + 0.5) * np.array([w, h])
    lo = np.floor(px.min(axis=1)).astype(np.int64) - 1
    hi = np.ceil(px.max(axis=1)).astype(np.int64) + 1
    out = np.concatenate([lo, hi], axis=1)
    out[behind] = (0, 0, w, h)
    out[:, [0, 2]] = out[:, [0, 2]].clip(0, w)
    out[:, [1, 3]] = out[:, [1, 3]].clip(0, h)
    return out


def tile_cover(rects: np.ndarray, size: tuple[int, int], tile: int = TILE_PX) -> list[Rect]:
    """Non-overlapping rectangles of whole tiles covering every pixel box in ``rects`` (B, 4):
    runs of tiles along each tile row, stacked where consecutive rows have the same run."""
    w, h = size
    cols, rows = -(-w // tile), -(-h // tile)
    rects = np.asarray(rects, np.int64).reshape(-1, 4)
    rects = rects[(rects[:, 2] > rects[:, 0]) & (rects[:, 3] > rects[:, 1])]
    c0, r0 = rects[:, 0] // tile, rects[:, 1] // tile
    c1, r1 = -(-rects[:, 2] // tile), -(-rects[:, 3] // tile)
    marks = np.zeros((rows + 1, cols + 1), np.int64)  # corners of each rect, summed twice
    np.add.at(marks, (r0, c0), 1)
    np.add.at(marks, (r0, c1), -1)
    np.add.at(marks, (r1, c0), -1)
    np.add.at(marks, (r1, c1), 1)
    mask = marks.cumsum(axis=0).cumsum(axis=1)[:rows, :cols] > 0
    out: list[Rect] = []
    open_runs: dict[tuple[int, int], int] = {}  # run (c0, c1) -> first row
    for r in range(rows + 1):
        runs: set[tuple[int, int]] = set()
        if r < rows:
            edges = np.flatnonzero(np.diff(np.r_[0, mask[r].astype(np.int8), 0]))
            runs = {(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)}
        for run in [k for k in open_runs if k not in runs]:
            first = open_runs.pop(run)
            out.append(_pixels(run, first, r, tile, size))
        for run in runs:
            open_runs.setdefault(run, r)
    return out


def _pixels(run: tuple[int, int], first: int, end: int, tile: int, size: tuple[int, int]) -> Rect:
    x0, y0 = run[0] * tile, first * tile
    x1, y1 = min(run[1] * tile, size[0]), min(end * tile, size[1])
    return (x0, y0, x1 - x0, y1 - y0)
