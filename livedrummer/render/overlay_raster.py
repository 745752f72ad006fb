"""The overlays painted into an RGBA image with numpy: the score strip and the angle graph.

The renderer blends the image over the frame (``shaders/overlay.frag``), so this module knows
nothing of OpenGL; it returns an ``(H, W, 4)`` uint8 array, top row first, with straight
(not premultiplied) alpha. Each strip keeps a *template*, everything that does not move
(the semi-transparent panel, lane lines and labels, the graph's grid, the legends), painted
once; a frame copies the template and paints what moves: note markers, the six angle curves
and the now-line (SMED's red bar, at the centre column ``W // 2``, on top of everything).

Everything is painted as boxes by :func:`fill_boxes`, which turns any number of boxes into
one list of pixel coordinates (``np.repeat`` over the boxes' areas) and assigns their colours
in one fancy-indexed write: no per-pixel or per-note Python loop. A note is a box in its lane:
hands are upright rectangles, feet diamonds (SMED drew "rectangles and diamonds"), sized and
brightened by velocity and coloured by limb (:data:`LIMB_RGB`). A curve is one column-wide box
per pixel column, from its value in that column to its value in the next, so steep strokes
draw without gaps. Legends are colour swatches with letters from :mod:`~.font5x7`.

Sizes: the score strip is 14 % and the graph 11 % of the frame's height (180 rows together at
720p), the font is scaled by whole pixels with the strip; :func:`overlay_image` gives the score
one lane per kit piece where those lanes fit their labels, else one per staff group. Limits: no
anti-aliasing; labels are dropped where lanes are lower than the font (small frames).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from livedrummer.render.font5x7 import ADVANCE, GLYPH_H, text_pixels, text_size
from livedrummer.render.overlay import AngleView, Lanes, OverlayModels, ScoreView

BACKGROUND = (10, 12, 22, 176)
LABEL_BOX = (0, 0, 0, 210)
LANE_LINE = (70, 76, 100, 255)
GRID_LINE = (56, 60, 80, 255)
TEXT = (215, 215, 225, 255)
NOW_LINE = (255, 40, 40, 255)
NOW_LINE_HALF_WIDTH = 1  # the line is 3 pixels wide
#: marker colour per limb: RH, LH, RF, LF, then not played (limb -1)
LIMB_RGB = np.array(
    [(255, 150, 50), (60, 150, 255), (90, 220, 110), (200, 120, 255), (150, 150, 150)], np.uint8
)
LIMB_LABELS = ("R", "L", "RF", "LF")
#: curve colour per :data:`~livedrummer.render.overlay.ANGLE_NAMES` column
ANGLE_RGB = np.array(
    [
        (255, 150, 50),
        (255, 230, 70),
        (255, 110, 190),
        (60, 130, 255),
        (60, 225, 230),
        (140, 230, 80),
    ],
    np.uint8,
)
ANGLE_LABELS = ("RS", "RE", "RW", "LS", "LE", "LW")
SCORE_FRACTION = 0.14
GRAPH_FRACTION = 0.11
MAX_DEG = 180.0


class ScoreSource(Protocol):
    """What a score strip paints: a file's :class:`~livedrummer.render.overlay.ScoreModel` or
    a live feed's :class:`~livedrummer.render.live_overlay.LiveScore`."""

    @property
    def lanes(self) -> Lanes: ...

    def view(self, now_s: float) -> ScoreView: ...


class AngleSource(Protocol):
    """What an angle strip paints: an ``AngleModel`` or a ``LiveAngles``."""

    def view(self, now_s: float) -> AngleView: ...


def fill_boxes(
    img: np.ndarray,
    top: np.ndarray,
    left: np.ndarray,
    height: np.ndarray,
    width: np.ndarray,
    rgba: np.ndarray,
    diamond: np.ndarray | None = None,
) -> None:
    """Paint boxes ``[top, top+height) x [left, left+width)`` (int arrays (n,)) with ``rgba``
    ((n, 4) or (4,) uint8); where ``diamond`` (bool (n,)) is set, only the inscribed diamond.
    Later boxes cover earlier ones; parts outside ``img`` are clipped."""
    top, left = np.asarray(top, np.int64), np.asarray(left, np.int64)
    height = np.maximum(np.asarray(height, np.int64), 0)
    width = np.maximum(np.asarray(width, np.int64), 0)
    counts = height * width
    total = int(counts.sum())
    if total == 0:
        return
    box = np.repeat(np.arange(counts.size), counts)
    local = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    w = width[box]
    dy = local // w
    dx = local - dy * w
    keep = np.ones(total, bool)
    if diamond is not None and np.any(diamond):
        cy = (height[box] - 1) / 2.0
        cx = (w - 1) / 2.0
        inside = (
            np.abs(dy - cy) / np.maximum(cy, 0.5) + np.abs(dx - cx) / np.maximum(cx, 0.5)
            <= 1.0 + 1e-9
        )
        keep = ~np.asarray(diamond, bool)[box] | inside
    rows = top[box] + dy
    cols = left[box] + dx
    keep &= (rows >= 0) & (rows < img.shape[0]) & (cols >= 0) & (cols < img.shape[1])
    colour = np.asarray(rgba, np.uint8)
    img[rows[keep], cols[keep]] = colour[box[keep]] if colour.ndim == 2 else colour


def draw_text(
    img: np.ndarray, text: str, top: int, left: int, scale: int, rgba: Sequence[int] = TEXT
) -> int:
    """Paint ``text`` with its top-left at (top, left); returns the column after it."""
    rows, cols = text_pixels(text, scale)
    rows, cols = rows + top, cols + left
    ok = (rows >= 0) & (rows < img.shape[0]) & (cols >= 0) & (cols < img.shape[1])
    img[rows[ok], cols[ok]] = rgba
    return left + text_size(text, scale)[1]


def draw_legend(
    img: np.ndarray, top: int, left: int, scale: int, colours: np.ndarray, labels: Sequence[str]
) -> int:
    """Swatch and label per entry, left to right; returns the column after the last."""
    side = GLYPH_H * scale
    x = left
    for rgb, label in zip(colours, labels, strict=True):
        fill_boxes(
            img,
            np.array([top]),
            np.array([x]),
            np.array([side]),
            np.array([side]),
            np.append(rgb, 255).astype(np.uint8),
        )
        x = draw_text(img, label, top, x + side + 2 * scale, scale) + 3 * ADVANCE * scale // 2
    return x


def marker_rgb(limb: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """(n, 3) uint8 marker colours: the limb's colour dimmed for soft notes (full at 127)."""
    base = LIMB_RGB[np.where(np.asarray(limb) < 0, len(LIMB_RGB) - 1, limb)].astype(np.float32)
    gain = 0.35 + 0.65 * np.clip(np.asarray(velocity, np.float32), 0, 127)[:, None] / 127.0
    out: np.ndarray = np.round(base * gain).astype(np.uint8)
    return out


def now_column(width: int) -> int:
    return width // 2


def font_scale(strip_h: int) -> int:
    return max(1, strip_h // 100)


def _panel(height: int, width: int) -> np.ndarray:
    img = np.empty((height, width, 4), np.uint8)
    img[:] = BACKGROUND
    return img


def _now_line(img: np.ndarray, top: int) -> None:
    c = now_column(img.shape[1])
    img[top:, max(c - NOW_LINE_HALF_WIDTH, 0) : c + NOW_LINE_HALF_WIDTH + 1] = NOW_LINE


class ScoreStrip:
    """The scrolling score at ``width`` x ``height`` pixels (see the module docstring)."""

    def __init__(self, model: ScoreSource, width: int, height: int) -> None:
        self.model, self.width, self.height = model, width, height
        self.scale = s = font_scale(height)
        self.band_h = (GLYPH_H + 4) * s  # legend row
        lanes = max(model.lanes.count, 1)
        self.lane_h = (height - self.band_h - 2) / lanes
        self.lane_centre = np.round(self.band_h + (np.arange(lanes) + 0.5) * self.lane_h)
        t = _panel(height, width)
        draw_legend(t, 2 * s, 4 * s, s, LIMB_RGB[:4], LIMB_LABELS)
        draw_text(t, "SCORE", 2 * s, width - text_size("SCORE", s)[1] - 4 * s, s)
        t[self.lane_centre.astype(np.int64)] = LANE_LINE
        if self.lane_h >= GLYPH_H * s + 1:
            label_w = text_size("XXX", s)[1] + 4 * s
            for row, label in zip(self.lane_centre, model.lanes.labels, strict=False):
                top = int(row) - GLYPH_H * s // 2
                t[top - s : top + GLYPH_H * s + s, 0:label_w] = LABEL_BOX
                draw_text(t, label, top, 2 * s, s)
        self.template = t

    def markers(self, view: ScoreView) -> tuple[np.ndarray, ...]:
        """Top, left, height, width, rgba and diamond of each visible note's marker."""
        v = view.velocity.astype(np.float64)
        half_h = np.maximum(np.round(0.5 * (self.lane_h - 1) * (0.45 + 0.55 * v / 127.0)), 1)
        feet = view.limb >= 2
        half_w = np.where(feet, half_h, np.maximum(np.round(0.6 * half_h), 1))
        centre_x = np.round(view.x * self.width)
        centre_y = self.lane_centre[view.lane]
        rgba = np.empty((v.size, 4), np.uint8)
        rgba[:, :3] = marker_rgb(view.limb, view.velocity)
        rgba[:, 3] = 255
        return (centre_y - half_h, centre_x - half_w, 2 * half_h + 1, 2 * half_w + 1, rgba, feet)

    def paint(self, out: np.ndarray, now_s: float) -> None:
        """Paint the strip at ``now_s`` into ``out`` ((height, width, 4) uint8)."""
        np.copyto(out, self.template)
        top, left, h, w, rgba, diamond = self.markers(self.model.view(now_s))
        fill_boxes(out, top, left, h, w, rgba, diamond)
        _now_line(out, self.band_h)


class AngleStrip:
    """The scrolling joint-angle graph at ``width`` x ``height`` pixels, 0..180 degrees."""

    def __init__(self, model: AngleSource, width: int, height: int) -> None:
        self.model, self.width, self.height = model, width, height
        self.scale = s = font_scale(height)
        self.band_h = (GLYPH_H + 4) * s
        self.plot_top = self.band_h + s
        self.plot_bottom = height - 2 * s  # the 0 degree row
        t = _panel(height, width)
        for deg in (0.0, 45.0, 90.0, 135.0, 180.0):
            t[self.row(np.array([deg])).astype(np.int64)] = GRID_LINE
        draw_legend(t, 2 * s, 4 * s, s, ANGLE_RGB, ANGLE_LABELS)
        title = "ANGLES 0-180"
        draw_text(t, title, 2 * s, width - text_size(title, s)[1] - 4 * s, s)
        self.template = t
        self.column_x = (np.arange(width) + 0.5) / width

    def row(self, degrees: np.ndarray) -> np.ndarray:
        """Pixel row (float) of an angle: 0 degrees at the bottom, 180 at the top."""
        span = self.plot_bottom - self.plot_top
        out: np.ndarray = self.plot_bottom - np.clip(degrees, 0.0, MAX_DEG) / MAX_DEG * span
        return out

    def curve_rows(self, now_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Per column, the curves' rows (W, 6) (int) and whether the column has data (W,)."""
        view = self.model.view(now_s)
        m = len(view.x)
        if m < 2:
            return np.zeros((self.width, 6), np.int64), np.zeros(self.width, bool)
        step = view.x[1] - view.x[0]
        f = (self.column_x - view.x[0]) / step
        valid = (f >= 0) & (f <= m - 1)
        i = np.clip(np.floor(f).astype(np.int64), 0, m - 2)
        frac = np.clip(f - i, 0.0, 1.0)[:, None]
        deg = view.degrees[i] * (1.0 - frac) + view.degrees[i + 1] * frac
        return np.round(self.row(deg)).astype(np.int64), valid

    def paint(self, out: np.ndarray, now_s: float) -> None:
        np.copyto(out, self.template)
        rows, valid = self.curve_rows(now_s)
        nxt = np.concatenate([rows[1:], rows[-1:]])
        nvalid = np.concatenate([valid[1:], [False]])
        nxt = np.where(nvalid[:, None], nxt, rows)
        lo = np.minimum(rows, nxt).T  # (6, W): curve by curve, so later curves cover earlier
        hi = np.maximum(rows, nxt).T
        cols = np.broadcast_to(np.arange(self.width), lo.shape)
        use = np.broadcast_to(valid, lo.shape)
        colour = np.repeat(
            np.append(ANGLE_RGB, np.full((6, 1), 255, np.uint8), axis=1), self.width, axis=0
        )
        fill_boxes(
            out,
            lo[use],
            cols[use],
            (hi - lo + 2)[use],
            np.ones(int(use.sum()), np.int64),
            colour[use.ravel()],
        )
        _now_line(out, self.band_h)


@dataclass(frozen=True)
class OverlayRect:
    """Where the overlay image goes in the frame: pixels, top-left origin."""

    x: int
    y: int
    width: int
    height: int


def strip_heights(frame_h: int, names: frozenset[str]) -> dict[str, int]:
    """Height in pixels of each enabled strip for a frame ``frame_h`` pixels high."""
    out = {}
    if "score" in names:
        out["score"] = max(round(SCORE_FRACTION * frame_h), 40)
    if "joints" in names:
        out["joints"] = max(round(GRAPH_FRACTION * frame_h), 32)
    total = sum(out.values())
    if total > frame_h // 2:  # tiny frames: the strips keep their proportions, half the frame
        out = {k: max(v * (frame_h // 2) // total, 1) for k, v in out.items()}
    return out


class OverlayImage:
    """The enabled strips stacked at the bottom of a frame, score above graph.

    :meth:`paint` returns the same array each call (painted in place); :attr:`rect` is where
    it goes. With no strip enabled, :attr:`empty` is true and nothing should be drawn."""

    def __init__(
        self,
        frame_size: tuple[int, int],
        names: frozenset[str],
        score: ScoreSource | None,
        angles: AngleSource | None,
    ) -> None:
        w, h = frame_size
        heights = strip_heights(h, names)
        self.strips: list[tuple[ScoreStrip | AngleStrip, int, int]] = []
        row = 0
        if "score" in heights and score is not None:
            self.strips.append((ScoreStrip(score, w, heights["score"]), row, heights["score"]))
            row += heights["score"]
        if "joints" in heights and angles is not None:
            self.strips.append((AngleStrip(angles, w, heights["joints"]), row, heights["joints"]))
            row += heights["joints"]
        self.image = np.zeros((row, w, 4), np.uint8)
        self.rect = OverlayRect(0, h - row, w, row)
        self.names = frozenset(names)
        self.frame_size = frame_size

    @property
    def empty(self) -> bool:
        return not self.strips

    def paint(self, now_s: float) -> np.ndarray:
        for strip, top, height in self.strips:
            strip.paint(self.image[top : top + height], now_s)
        image: np.ndarray = self.image
        return image


def overlay_image(
    frame_size: tuple[int, int], names: frozenset[str], models: OverlayModels
) -> OverlayImage:
    """The overlay of the strips ``names`` for frames of ``frame_size`` (W, H); the score has a
    lane per kit piece where the lanes are tall enough for their labels, else one per group."""
    score = None
    if "score" in names:
        score = models.score()
        height = strip_heights(frame_size[1], names)["score"]
        s = font_scale(height)
        if (height - (GLYPH_H + 4) * s - 2) / max(score.lanes.count, 1) < (GLYPH_H + 1) * s:
            score = models.score(grouped=True)
    return OverlayImage(frame_size, names, score, models.angles if "joints" in names else None)
