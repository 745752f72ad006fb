"""Quick contacts: a predicted hit's contact pose, computed from a snapshot, in a millisecond.

The synthesizer's curves are rebuilt (10-20 ms) whenever its window of notes changes; a hit
that was predicted does not need to wait for that, because the current curves already strike
the guessed piece, with the guessed hand, at the guess's time. :func:`quick_contact` takes a
:class:`QuickState` (what :meth:`~livedrummer.live.synth.LiveSynth.quick_state` copies out of
the synthesizer: its curves, the cross-fade from the previous ones, its guesses, what it has
published and the samples it holds ahead) and an arriving onset, and returns the pose samples
to send at once: the current curves from the end of what was published up to the hit, then
the guess's contact shown at the hit's onset + D. Nothing in the state is changed, so a
service can compute this on its input thread while another thread re-animates
(:mod:`services.synth.service`); the re-animated curves replace these samples a moment later.

A hit qualifies when a guess of the same piece and zone lies within a third of that hand's
period of it and the current curves were built with that guess. Other hits (no pattern yet,
another piece) wait for the re-animation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from livedrummer.body.animation import Animation
from livedrummer.body.rig import Rig
from livedrummer.body.sample import sample_poses
from livedrummer.live.predict import Guess
from livedrummer.sticking.result import Sticking
from livedrummer.vocabulary import INSTRUMENTS


@dataclass
class Curves:
    """One animation of the synthesizer's window, and what it was built from."""

    anim: Animation
    sticking: Sticking
    key: tuple[object, ...]
    contacts_s: np.ndarray  # committed contacts (performance time), sorted


@dataclass(frozen=True)
class QuickState:
    """A read-only copy of what :func:`quick_contact` needs (see the module docstring)."""

    rig: Rig
    dtype: np.dtype
    delay_s: float
    rate_hz: float
    curves: Curves | None
    old: Curves | None  # the curves being faded out, with the fade (start, length)
    fade: tuple[float, float]
    guesses: tuple[Guess, ...]
    horizon_s: float | None  # the last performance time published
    cache_t: np.ndarray  # samples of ``curves`` held ahead of the horizon
    cache_rows: np.ndarray


def sample_curves(
    curves: Curves, old: Curves | None, fade: tuple[float, float], times: np.ndarray
) -> tuple[np.ndarray, bool]:
    """Pose records at ``times``, cross-faded from ``old`` over ``fade``; and whether the fade
    is over for all of them (then ``old`` can be dropped)."""
    rows = sample_poses(curves.anim, curves.sticking, times)
    if old is None:
        return rows, True
    f0, flen = fade
    w = np.clip((times - f0) / flen, 0.0, 1.0) if flen > 0 else np.ones_like(times)
    fading = w < 1.0
    if not fading.any():
        return rows, True
    prev = sample_poses(old.anim, old.sticking, times[fading])
    blend_rows(prev, rows[fading], w[fading])
    rows[fading] = prev
    return rows, False


def blend_rows(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> None:
    """``a`` becomes ``(1 - w) a + w b`` in place: positions and channels linearly, rotations
    by normalised linear interpolation on the same hemisphere."""
    wc = w.astype(np.float32)
    for name in ("position", "swing", "lift", "glow"):
        shape = (-1,) + (1,) * (a[name].ndim - 1)
        a[name] = a[name] + (b[name] - a[name]) * wc.reshape(shape)
    qa, qb = a["rotation"], b["rotation"].copy()
    flip = np.sum(qa * qb, axis=-1) < 0
    qb[flip] *= -1.0
    q = qa + (qb - qa) * wc[:, None, None]
    a["rotation"] = q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), 1e-12)


def piece_of(rig: Rig, instrument: int) -> int:
    """The kit piece index playing a note map's instrument code, or -1."""
    piece = rig.kit.resolve(INSTRUMENTS[instrument])
    if piece is None:
        return -1
    return rig.kit.pieces.index(piece)


def quick_contact(state: QuickState, row: np.ndarray | np.void) -> tuple[np.ndarray, np.ndarray]:
    """Show times and pose records to send at once for onset ``row`` (both empty when the hit
    was not predicted; see the module docstring)."""
    none = (np.zeros(0), np.zeros(0, state.dtype))
    curves = state.curves
    if curves is None:
        return none
    t = float(row["time_s"])
    piece = piece_of(state.rig, int(row["instrument"]))
    drawn = curves.key[1]
    for g in state.guesses:
        if not (
            isinstance(drawn, tuple)
            and (g.time_s, g.limb, g.piece) in drawn
            and g.piece == piece
            and g.zone == int(row["zone"])
            and abs(g.time_s - t) <= g.period_s / 3
        ):
            continue
        lo = state.horizon_s if state.horizon_s is not None else t
        held = (state.cache_t > lo) & (state.cache_t < t)
        times, rows = state.cache_t[held], state.cache_rows[held]
        end = float(state.cache_t[-1]) if state.cache_t.size else lo
        if max(end, lo) < t:  # the held samples stop short of the hit: fill the grid
            step = 1.0 / state.rate_hz
            grid = np.arange(math.floor(max(end, lo) / step) + 1, math.ceil(t / step)) * step
            c = curves.contacts_s
            grid = np.unique(np.concatenate([grid, c[(c > max(end, lo)) & (c < t)]]))
            grid = grid[(grid > max(end, lo)) & (grid < t)]
            if grid.size:
                more, _ = sample_curves(curves, state.old, state.fade, grid)
                times, rows = np.concatenate([times, grid]), np.concatenate([rows, more])
        contact, _ = sample_curves(curves, state.old, state.fade, np.array([g.time_s]))
        shows = np.append(times, t) + state.delay_s
        return shows, np.concatenate([rows, contact])
    return none


def merge_quick(
    parts: list[tuple[np.ndarray, np.ndarray]], dtype: np.dtype
) -> tuple[np.ndarray, np.ndarray]:
    """Several hits' quick samples as one batch, ascending: a later hit's sample wins a show
    time both have (a chord: the last one)."""
    merged: dict[float, np.ndarray] = {}
    for shows, rows in parts:
        merged.update(zip(shows.tolist(), rows, strict=True))
    if not merged:
        return np.zeros(0), np.zeros(0, dtype)
    show = np.array(sorted(merged))
    out = np.array([merged[k] for k in show.tolist()], dtype=dtype)
    out["time_s"] = (show - show[0]).astype(np.float32)
    return show, out
