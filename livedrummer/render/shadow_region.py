"""Where a frame differs from a cached still picture of the kit: the screen tiles to redraw.

The renderer's static layer (``services/display/passes/layer.py``) caches the kit at rest, lit
and shadowed by the kit at rest. A frame differs from it where a piece is not at rest (its old
and its new pixels) and where anything not in the cache (the drummer, the sticks, a piece away
from its rest pose) casts or cast a shadow onto the kit or the floor. Such a shadow lies inside
the caster's shadow volume from the key spot, between the caster and the floor: the convex
hull of the caster's box corners and of the same corners pushed along the light's rays down to
the floor plane (for a point light above the box, every shadowed point at or above the floor is
in that hull). A convex hull's perspective image lies in the box of its projected corners, so
:func:`box_rects` and :func:`shadow_rects` give conservative pixel boxes; :func:`tile_cover`
turns their union into few non-overlapping rectangles of whole tiles.

Pure numpy, no GPU, vectorised over boxes. The caller pads boxes for what the shadow lookup
reaches beyond the caster (the normal offset and the filter's footprint). Limits: a light at or
below a box's top, or a point behind the camera's eye plane, gives the whole frame (correct, no
saving); axis-aligned boxes over-cover slanted shadows.
"""

from __future__ import annotations

import numpy as np

#: tile side in pixels of the redrawn region
TILE_PX = 32
#: metres between the horizontal planes a shadow volume is cut at
SLAB_M = 0.2

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


def shadow_rects(lo: np.ndarray, hi: np.ndarray, light: np.ndarray, receivers_lo: np.ndarray,
                 receivers_hi: np.ndarray, view_proj: np.ndarray, size: tuple[int, int],
                 slab_m: float = SLAB_M) -> np.ndarray:  # fmt: skip
    """Pixel boxes (K, 4) holding every shadow the caster boxes ``lo``..``hi`` (B, 3; world
    metres) cast from ``light`` onto the receiver boxes ``receivers_lo``..``receivers_hi``
    (R, 3), seen through ``view_proj``.

    A caster's shadow volume lies in the cone of rays from the light through its box; the cone
    is cut into horizontal slabs ``slab_m`` thick, from the lowest receiver up to the caster's
    top, and within a slab it lies in the box of its two cross-sections (the projections of
    the caster's corners onto the slab's planes). Each slab box met by a receiver box gives the
    pixel box of their intersection."""
    light = np.asarray(light, np.float64)
    lo, hi = np.atleast_2d(lo).astype(np.float64), np.atleast_2d(hi).astype(np.float64)
    if not len(lo):
        return np.zeros((0, 4), np.int64)
    if (light[2] - hi[:, 2]).min() <= 1e-3:
        return np.array([[0, 0, *size]], np.int64)
    base = float(np.min(receivers_lo[:, 2]))
    levels = base + slab_m * np.arange(int(np.ceil((hi[:, 2].max() - base) / slab_m)) + 1)
    za, zb = levels[:-1], levels[1:]  # (S,)
    corners = box_corners(lo, hi)  # (B, 8, 3)
    drop = light[2] - corners[..., 2]  # (B, 8)

    def section(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = (light[2] - z)[None, :, None] / drop[:, None, :]  # (B, S, 8)
        xy = light[:2] + t[..., None] * (corners[:, None, :, :2] - light[:2])  # (B, S, 8, 2)
        return xy.min(axis=2), xy.max(axis=2)

    a_lo, a_hi = section(za)
    b_lo, b_hi = section(zb)
    s_lo = np.concatenate([np.minimum(a_lo, b_lo), np.broadcast_to(za[None, :, None],
                           (len(lo), len(za), 1))], axis=2)  # fmt: skip
    s_hi = np.concatenate([np.maximum(a_hi, b_hi), np.broadcast_to(zb[None, :, None],
                           (len(lo), len(za), 1))], axis=2)  # fmt: skip
    under = za[None, :] < hi[:, 2:3]  # slabs below each caster's top
    s_lo, s_hi = s_lo[under], s_hi[under]  # (K, 3)
    i_lo = np.maximum(s_lo[:, None, :], receivers_lo[None, :, :])  # (K, R, 3)
    i_hi = np.minimum(s_hi[:, None, :], receivers_hi[None, :, :])
    met = (i_lo < i_hi).all(axis=2)
    if not met.any():
        return np.zeros((0, 4), np.int64)
    return box_rects(box_corners(i_lo[met], i_hi[met]), view_proj, size)


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
