"""The practice readout painted for the window: early/late meter, streak, accuracy, summaries.

The practice rig (``livedrummer practice``) sends the display one small message per event
(the pass planned, each hit's provisional judgement, each pass's summary); :class:`PracticePanel`
keeps what the readout shows from them and :func:`panel_image` paints it as an RGBA image the
renderer blends over the frame (``Renderer.draw_overlay``), bottom left, clear of the window's
own readout (top left) and the strips (bottom). What it shows:

* the pass line: pass number, bars, bpm, and the teacher's mode;
* the meter: a bar from -window to +window (early left, late right), the level's on-time band
  shaded, the centre line, the last :data:`HISTORY` hits as thin ticks and the newest as a
  block, green when on time, amber when early or late (a hit that matched no note has no
  place on it: its line says so);
* the newest hit in words: piece, offset in ms, on time / early / late, streak, running
  accuracy (the provisional figures of :mod:`livedrummer.practice.live`);
* after a pass, its summary (the judged result's first :data:`SUMMARY_LINES` lines as the
  terminal prints them: totals, timing, accuracy and score) until the next pass's first hit.

The image changes only when a message changes the panel (``version``), so a display repaints
and uploads it then and reuses it between. Pure numpy and the 5x7 font; upper-case ASCII.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from livedrummer.render.font5x7 import GLYPH_H, GLYPHS, text_size
from livedrummer.render.overlay_raster import draw_text

PANEL_RGBA = (8, 10, 18, 190)
TEXT_RGBA = (235, 235, 235, 255)
DIM_RGBA = (150, 150, 165, 255)
BAR_RGBA = (60, 64, 84, 255)
BAND_RGBA = (40, 110, 60, 255)
CENTRE_RGBA = (230, 230, 230, 255)
ON_TIME_RGBA = (70, 230, 90, 255)
OFF_TIME_RGBA = (255, 170, 40, 255)
HISTORY = 8
SUMMARY_LINES = 3  # totals, timing, accuracy and score; the per-piece lines stay in the terminal
PAD = 6
METER_CELLS = 100  # the meter is this many scale-pixels wide


@dataclass
class HitView:
    piece: str
    offset_ms: float | None
    on_time: bool
    streak: int
    accuracy_pct: float


@dataclass
class PracticePanel:
    """What the readout shows (see the module docstring); fed with :meth:`apply`."""

    window_ms: float = 100.0
    level_ms: float = 40.0
    teacher: str = ""
    pass_line: str = "PRACTICE: COUNT-IN"
    hits: list[HitView] = field(default_factory=list)
    summary: list[str] = field(default_factory=list)
    version: int = 0

    def apply(self, msg: dict[str, Any]) -> None:
        """One message of the rig: ``{"plan": ...}``, ``{"hit": ...}`` or ``{"summary": ...}``
        (see ``services.practice.readout_out``). Raises KeyError/TypeError/ValueError on a
        malformed one (the display counts it)."""
        if "plan" in msg:
            p = msg["plan"]
            self.window_ms = float(p["window_ms"])
            self.level_ms = float(p["level_ms"])
            bars = p["bars"]
            self.pass_line = (
                f"PASS {int(p['pass'])}  BARS {int(bars[0])}-{int(bars[1])}  "
                f"{float(p['bpm']):.1f} BPM"
            )
            self.teacher = str(p.get("teacher", ""))
        elif "hit" in msg:
            h = msg["hit"]
            off = h["offset_ms"]
            if self.summary:  # a new pass's hits: its summary has been read
                self.summary = []
                self.hits = []
            self.hits.append(
                HitView(
                    str(h["piece"]),
                    None if off is None else float(off),
                    bool(h["on_time"]),
                    int(h["streak"]),
                    float(h["accuracy_pct"]),
                )
            )
            self.hits = self.hits[-HISTORY:]
        elif "summary" in msg:
            s = msg["summary"]
            self.summary = [str(x) for x in s["lines"]][:SUMMARY_LINES]
            self.pass_line = f"PASS {int(s['pass'])} DONE"
        else:
            raise KeyError("expected plan, hit or summary")
        self.version += 1

    def lines(self) -> list[str]:
        """The text lines under the meter."""
        out = [self.pass_line + (f"   TEACHER {self.teacher}" if self.teacher else "")]
        if self.hits:
            h = self.hits[-1]
            if h.offset_ms is None:
                what = "NO NOTE OF IT HERE"
            else:
                word = "ON TIME" if h.on_time else ("LATE" if h.offset_ms > 0 else "EARLY")
                what = f"{h.offset_ms:+.1f} MS {word}"
            out.append(f"{h.piece}  {what}")
            out.append(f"STREAK {h.streak}   ACCURACY {h.accuracy_pct:.1f} %")
        else:
            out += ["PLAY ALONG", ""]
        out += self.summary
        return [fontable(line) for line in out]


def fontable(text: str) -> str:
    """``text`` in the 5x7 font's characters: upper case, ``%`` as ``PCT``, ``±`` as ``+-``,
    anything else it lacks as a space."""
    text = text.upper().replace("%", "PCT").replace("±", "+-").replace(";", ",")
    return "".join(c if c in GLYPHS else " " for c in text)


def _box(img: np.ndarray, top: int, left: int, h: int, w: int, rgba: tuple[int, ...]) -> None:
    img[max(0, top) : max(0, top + h), max(0, left) : max(0, left + w)] = rgba


def panel_image(panel: PracticePanel, scale: int = 2) -> np.ndarray:
    """The readout (see the module docstring): (h, w, 4) uint8, straight alpha, top row first."""
    lines = panel.lines()
    line_h = (GLYPH_H + 3) * scale
    meter_w = METER_CELLS * scale * 2
    meter_h = 8 * scale
    width = max([meter_w] + [text_size(t, scale)[1] for t in lines]) + 2 * PAD
    height = 2 * PAD + meter_h + 2 * scale + len(lines) * line_h
    img = np.empty((height, width, 4), np.uint8)
    img[:] = PANEL_RGBA
    top, left = PAD, PAD
    _box(img, top + meter_h // 3, left, meter_h // 3, meter_w, BAR_RGBA)
    half = meter_w // 2
    px_ms = half / max(panel.window_ms, 1e-6)

    def column(offset_ms: float) -> int:
        return (
            left
            + half
            + round(float(np.clip(offset_ms, -panel.window_ms, panel.window_ms)) * px_ms)
        )

    band = round(panel.level_ms * px_ms)
    _box(img, top + meter_h // 3, left + half - band, meter_h // 3, 2 * band, BAND_RGBA)
    _box(img, top, left + half - scale // 2, meter_h, max(1, scale), CENTRE_RGBA)
    for h in panel.hits[:-1]:
        if h.offset_ms is not None:
            _box(
                img,
                top + meter_h // 4,
                column(h.offset_ms) - scale // 2,
                meter_h // 2,
                max(1, scale),
                DIM_RGBA,
            )
    if panel.hits and panel.hits[-1].offset_ms is not None:
        last = panel.hits[-1]
        rgba = ON_TIME_RGBA if last.on_time else OFF_TIME_RGBA
        assert last.offset_ms is not None
        _box(img, top, column(last.offset_ms) - 2 * scale, meter_h, 4 * scale, rgba)
    y = top + meter_h + 2 * scale
    for i, text in enumerate(lines):
        rgba = TEXT_RGBA if i < 3 else DIM_RGBA
        draw_text(img, text, y + i * line_h, left, scale, rgba)
    return img
