"""Practice reports: one self-contained HTML page per take, and one of progress over days.

People look at a report rather than read it, so each page is a few plots with a line of
figures above them. Plots are drawn by matplotlib with its non-interactive Agg backend (no
screen, no GUI toolkit) as SVG and written inline into the page: the file has no external
reference at all (no script, no font, no image file) and opens the same offline, mailed, or on
a phone. Everything here is pure: arrays and result objects in, an HTML string out; the caller
writes the file.

A take's page (:func:`take_report`):

- **timing per note over time**, one row of points per piece (offset in ms against the
  reference time; the EASY and HARD windows shaded; wrong pieces and misses marked on the
  zero line);
- **offset histograms** per piece (5 ms bins across the matching window);
- **tempo drift against the click**: per bar, the player's tempo (the slope of played against
  reference times over that bar's hits, at least 3) beside the reference's, and the bar's
  median offset; a player rushing a fill shows as the tempo line rising above the reference;
- **results per limb**, from the sticking of the reference (who should have played each
  note): perfect / good / ok / wrong piece / missed per limb, and each limb's mean offset.

Limits: SVGs of very long takes (thousands of notes) grow to a few hundred kB; the drift
needs at least 3 hits in a bar to be drawn for that bar.
"""

from __future__ import annotations

import html
import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.practice.grade import EASY_WINDOW_MS, HARD_WINDOW_MS, note_grades, window_words
from livedrummer.practice.match import PIECES, Result

_GRADE_COLOURS = {
    "perfect": "#2a9d3f",
    "good": "#8cc63f",
    "ok": "#f0a30a",
    "wrong_piece": "#8e44ad",
    "missed": "#d62828",
}
_LIMBS = ("RH", "LH", "RF", "LF")

_STYLE = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1000px; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.1em; margin-top: 1.6em; }
.figures { font-size: 1.05em; line-height: 1.5; }
.plot svg { width: 100%; height: auto; }
table { border-collapse: collapse; } td, th { padding: 2px 10px; text-align: right; }
th { border-bottom: 1px solid #999; } td:first-child, th:first-child { text-align: left; }
"""


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _svg(fig: Any) -> str:
    """The figure as inline SVG markup (its XML header dropped), then closed."""
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight")
    _pyplot().close(fig)
    text = buf.getvalue()
    return text[text.index("<svg") :]


def _page(title: str, body: Sequence[str]) -> str:
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>\n"
        + "\n".join(body)
        + "\n</body></html>\n"
    )


def _plot(title: str, svg: str) -> str:
    return f"<h2>{html.escape(title)}</h2>\n<div class='plot'>{svg}</div>"


def take_report(
    result: dict[str, Any],
    notes: np.ndarray,
    limbs: Sequence[str | None],
    bar_of: np.ndarray,
    bar_bpm: np.ndarray,
) -> str:
    """The HTML page of one judged take.

    ``result``: the :func:`~livedrummer.practice.grade.summary` object; ``notes``: the
    matching's NOTE_DTYPE rows; ``limbs``: the limb name (``RH`` …) that plays each of those
    notes in the reference's sticking, or None; ``bar_of``: each note's bar index;
    ``bar_bpm``: the reference tempo of each bar.
    """
    grades = note_grades(notes)
    words = window_words(result)
    title = f"Practice: {Path(str(result.get('reference', 'take'))).name}"
    figures = (
        f"<p class='figures'><b>{result['hits']}</b> of {result['reference_notes']} notes hit, "
        f"{result['wrong_piece']} wrong piece, {result['missed']} missed, "
        f"{result['extra']} extra. Accuracy <b>{result['accuracy_pct']:.1f} %</b> "
        f"({words['on_time']}), score <b>{result['score']:.1f}</b>/100. "
        + (
            f"Timing: mean {result['mean_offset_ms']:+.1f} ms (positive = late), "
            f"sd {result['sd_offset_ms']:.1f} ms."
            if result["mean_offset_ms"] is not None
            else "No hits."
        )
        + f"</p>\n<p>Take: {html.escape(str(result.get('take', '')))}; hits within the "
        f"{words['hits']}; perfect {words['perfect']}, good {words['good']}, "
        f"ok {words['ok']}.</p>"
    )
    body = [
        f"<h1>{html.escape(title)}</h1>",
        figures,
        _plot("Timing of each note, per piece", _timeline_svg(notes, grades, result)),
        _plot("Offset histograms", _histograms_svg(notes, result)),
        _plot("Tempo drift against the reference", _drift_svg(notes, bar_of, bar_bpm)),
        _plot("Results per limb (sticking of the reference)", _limbs_svg(grades, notes, limbs)),
        _piece_table(result),
    ]
    return _page(title, body)


def _pieces_in(notes: np.ndarray) -> list[int]:
    return sorted(set(notes["piece"].tolist()))


def _timeline_svg(notes: np.ndarray, grades: list[str], result: dict[str, Any]) -> str:
    plt = _pyplot()
    pieces = _pieces_in(notes) or [0]
    window = float(result["match_window_ms"])
    fig, axes = plt.subplots(
        len(pieces), 1, figsize=(10, 1.0 + 1.5 * len(pieces)), sharex=True, squeeze=False
    )
    grade_arr = np.array(grades, dtype=object)
    for ax, code in zip(axes[:, 0], pieces, strict=True):
        rows = notes["piece"] == code
        ax.axhspan(-EASY_WINDOW_MS, EASY_WINDOW_MS, color="#e8f5e9", zorder=0)
        ax.axhspan(-HARD_WINDOW_MS, HARD_WINDOW_MS, color="#c8e6c9", zorder=0)
        ax.axhline(0, color="#555", lw=0.6)
        for grade, colour in _GRADE_COLOURS.items():
            pick = rows & (grade_arr == grade)
            if not pick.any():
                continue
            t = notes["time_s"][pick]
            off = notes["offset_ms"][pick]
            y = np.where(np.isnan(off), 0.0, off)
            marker = "x" if grade in ("missed", "wrong_piece") else "o"
            ax.scatter(t, y, s=12, c=colour, marker=marker, label=grade.replace("_", " "))
        extra_t = [e["time_s"] for e in result.get("extra_notes", ()) if e["piece"] == PIECES[code]]
        if extra_t:
            ax.scatter(
                extra_t,
                np.full(len(extra_t), 0.85 * window),
                s=14,
                c="#777",
                marker="v",
                label="extra",
            )
        ax.set_ylim(-window, window)
        ax.set_ylabel(f"{PIECES[code]}\nms", fontsize=8)
        ax.tick_params(labelsize=8)
    handles: dict[str, Any] = {}
    for ax in axes[:, 0]:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    axes[0, 0].legend(handles.values(), handles.keys(), fontsize=7, ncol=6, loc="upper right")
    axes[-1, 0].set_xlabel("time (s) from the start of the reference or loop, at the tempo played")
    return _svg(fig)


def _histograms_svg(notes: np.ndarray, result: dict[str, Any]) -> str:
    plt = _pyplot()
    window = float(result["match_window_ms"])
    hit = notes["result"] == Result.HIT
    pieces = [c for c in _pieces_in(notes) if (hit & (notes["piece"] == c)).any()] or [0]
    cols = min(4, len(pieces))
    rows = (len(pieces) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(10, 2.2 * rows), squeeze=False)
    bins = np.arange(-window, window + 5.0, 5.0)
    for k, ax in enumerate(axes.ravel()):
        if k >= len(pieces):
            ax.axis("off")
            continue
        code = pieces[k]
        off = notes["offset_ms"][hit & (notes["piece"] == code)]
        ax.hist(off, bins=bins, color="#3a7bd5")
        ax.axvline(0, color="#555", lw=0.6)
        mean = f", mean {off.mean():+.1f}" if off.size else ""
        ax.set_title(f"{PIECES[code]} ({off.size}{mean})", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("offset ms (late +)", fontsize=7)
    fig.tight_layout()
    return _svg(fig)


def bar_drift(
    notes: np.ndarray, bar_of: np.ndarray, bar_bpm: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per bar with ≥ 3 hits: (bar, player tempo bpm, median offset ms); see the docstring."""
    hit = notes["result"] == Result.HIT
    bars, tempo, median = [], [], []
    for bar in np.unique(bar_of[hit]).tolist():
        pick = hit & (bar_of == bar)
        ref_t = notes["time_s"][pick]
        if ref_t.size < 3 or np.ptp(ref_t) <= 0:
            continue
        played_t = ref_t + notes["offset_ms"][pick] / 1e3
        slope = float(np.polyfit(ref_t, played_t, 1)[0])
        if slope <= 0:
            continue
        bars.append(bar)
        tempo.append(float(bar_bpm[bar]) / slope)
        median.append(float(np.median(notes["offset_ms"][pick])))
    return np.array(bars, dtype=np.int64), np.array(tempo), np.array(median)


def _drift_svg(notes: np.ndarray, bar_of: np.ndarray, bar_bpm: np.ndarray) -> str:
    plt = _pyplot()
    from matplotlib.ticker import MaxNLocator

    bars, tempo, median = bar_drift(notes, bar_of, bar_bpm)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(10, 4.2), sharex=True)
    shown = np.unique(bar_of)
    ax1.step(shown + 1, bar_bpm[shown], where="mid", color="#555", label="reference")
    ax1.plot(bars + 1, tempo, "o-", color="#3a7bd5", ms=3, label="you")
    ax1.set_ylabel("bpm")
    if shown.size:  # at least ±5 bpm around the reference, so a hair's drift looks like one
        values = np.concatenate([bar_bpm[shown], tempo])
        mid = float(np.median(bar_bpm[shown]))
        span = max(5.0, float(np.max(np.abs(values - mid))) * 1.1)
        ax1.set_ylim(mid - span, mid + span)
    ax2.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax1.legend(fontsize=8)
    ax2.axhline(0, color="#555", lw=0.6)
    ax2.bar(bars + 1, median, color=np.where(median > 0, "#e07a5f", "#3d85c6"))
    ax2.set_ylabel("median offset ms\n(late +)", fontsize=8)
    ax2.set_xlabel("bar")
    return _svg(fig)


def _limbs_svg(grades: list[str], notes: np.ndarray, limbs: Sequence[str | None]) -> str:
    plt = _pyplot()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.0))
    names = [limb or "none" for limb in limbs]
    present = [limb for limb in (*_LIMBS, "none") if limb in names]
    left = np.zeros(len(present))
    for grade, colour in _GRADE_COLOURS.items():
        counts = np.array(
            [
                sum(1 for n, g in zip(names, grades, strict=True) if n == limb and g == grade)
                for limb in present
            ],
            dtype=float,
        )
        ax1.barh(present, counts, left=left, color=colour, label=grade.replace("_", " "))
        left += counts
    ax1.invert_yaxis()
    ax1.set_xlabel("notes")
    ax1.legend(fontsize=7, ncol=3, loc="lower right")
    hit = notes["result"] == Result.HIT
    arr = np.array(names, dtype=object)
    means = [
        float(notes["offset_ms"][hit & (arr == limb)].mean())
        if (hit & (arr == limb)).any()
        else 0.0
        for limb in present
    ]
    ax2.barh(present, means, color=["#e07a5f" if m > 0 else "#3d85c6" for m in means])
    ax2.axvline(0, color="#555", lw=0.6)
    ax2.invert_yaxis()
    ax2.set_xlabel("mean offset ms (late +)")
    fig.tight_layout()
    return _svg(fig)


def _piece_table(result: dict[str, Any]) -> str:
    head = (
        "<tr><th>piece</th><th>notes</th><th>hits</th><th>wrong</th><th>missed</th>"
        "<th>extra</th><th>mean ms</th><th>sd ms</th><th>accuracy %</th></tr>"
    )
    rows = []
    for piece, r in result["per_piece"].items():
        mean = "" if r["mean_offset_ms"] is None else f"{r['mean_offset_ms']:+.1f}"
        sd = "" if r["sd_offset_ms"] is None else f"{r['sd_offset_ms']:.1f}"
        rows.append(
            f"<tr><td>{html.escape(piece)}</td><td>{r['reference_notes']}</td><td>{r['hits']}</td>"
            f"<td>{r['wrong_piece']}</td><td>{r['missed']}</td><td>{r['extra']}</td>"
            f"<td>{mean}</td><td>{sd}</td><td>{r['accuracy_pct']:.1f}</td></tr>"
        )
    return "<h2>Per piece</h2>\n<table>" + head + "".join(rows) + "</table>"


def history_report(sessions: Sequence[dict[str, Any]]) -> str:
    """The HTML page of progress over days: per day, the best and mean score and accuracy,
    the mean timing offset and its spread, and the notes played (rows as
    :meth:`services.practice.store.PracticeStore.sessions` gives them)."""
    plt = _pyplot()
    title = "Practice progress"
    if not sessions:
        return _page(title, [f"<h1>{title}</h1>", "<p>No practice sessions yet.</p>"])
    days = sorted({str(s["started"])[:10] for s in sessions})
    by_day = {d: [s for s in sessions if str(s["started"])[:10] == d] for d in days}
    x = np.arange(len(days))

    def per_day(key: str, fn: Any) -> np.ndarray:
        out = []
        for d in days:
            vals = [float(s[key]) for s in by_day[d] if s[key] is not None]
            out.append(fn(vals) if vals else np.nan)
        return np.array(out)

    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(10, 7.5), sharex=True)
    ax1.plot(x, per_day("score", max), "o-", label="best score", color="#2a9d3f")
    ax1.plot(x, per_day("score", np.mean), "o--", label="mean score", color="#8cc63f")
    ax1.plot(x, per_day("accuracy_pct", np.mean), "s-", label="mean accuracy %", color="#3a7bd5")
    ax1.set_ylim(0, 100)
    ax1.legend(fontsize=8)
    mean = per_day("mean_offset_ms", np.mean)
    sd = per_day("sd_offset_ms", np.mean)
    ax2.axhline(0, color="#555", lw=0.6)
    ax2.errorbar(x, mean, yerr=sd, fmt="o-", color="#e07a5f", capsize=3)
    ax2.set_ylabel("offset ms\n(mean ± sd)", fontsize=8)
    ax3.bar(x, per_day("reference_notes", sum), color="#999")
    ax3.set_ylabel("notes judged", fontsize=8)
    ax3.set_xticks(x, days, rotation=30, fontsize=8)
    fig.tight_layout()
    last = sessions[-1]
    body = [
        f"<h1>{title}</h1>",
        f"<p class='figures'>{len(sessions)} sessions over {len(days)} days; the last "
        f"({html.escape(str(last['started']))}): score <b>{float(last['score']):.1f}</b>, "
        f"accuracy <b>{float(last['accuracy_pct']):.1f} %</b>.</p>",
        _plot("Score, accuracy and timing by day", _svg(fig)),
    ]
    return _page(title, body)
