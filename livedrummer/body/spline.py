"""Kochanek-Bartels (tension, continuity, bias) splines, evaluated for many times at once.

SMED interpolates joint values between keyframes with CTB splines and models stick impact
with the continuity parameter: continuity -1 at a contact key makes the incoming and outgoing
tangents the two one-sided slopes, a corner where the stick reverses, while preparation and
rebound keys stay smooth. Keys are non-uniformly spaced in time, so tangents are computed as
velocities (value per second) from each side's slope and scaled by the segment's duration;
this keeps the curve through every key exactly and avoids the overshoot the uniform formula
gives next to a short segment. Values are ``(K, C)``: C channels share the key times.
Outside the keys the curve holds the end values.
"""

from __future__ import annotations

import numpy as np


def tangents(
    times: np.ndarray,
    values: np.ndarray,
    tension: np.ndarray,
    continuity: np.ndarray,
    bias: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Incoming and outgoing velocities (K, C) at every key."""
    k = times.shape[0]
    dt = np.maximum(np.diff(times), 1e-9)[:, None]
    slope = np.diff(values, axis=0) / dt  # (K-1, C)
    zero = np.zeros((1, values.shape[1]))
    before = np.concatenate([zero, slope], axis=0) if k > 1 else np.zeros_like(values)
    after = np.concatenate([slope, zero], axis=0) if k > 1 else np.zeros_like(values)
    t, c, b = (np.asarray(x, dtype=np.float64)[:, None] for x in (tension, continuity, bias))
    outgoing = (1 - t) * ((1 + b) * (1 + c) * before + (1 - b) * (1 - c) * after) / 2
    incoming = (1 - t) * ((1 + b) * (1 - c) * before + (1 - b) * (1 + c) * after) / 2
    return incoming, outgoing


def evaluate(
    times: np.ndarray,
    values: np.ndarray,
    sample_s: np.ndarray,
    tension: np.ndarray | None = None,
    continuity: np.ndarray | None = None,
    bias: np.ndarray | None = None,
) -> np.ndarray:
    """The spline through (times, values) at ``sample_s`` -> (N, C)."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim == 1:
        return evaluate(times, values[:, None], sample_s, tension, continuity, bias)[:, 0]
    k = times.shape[0]
    zeros = np.zeros(k)
    incoming, outgoing = tangents(
        times,
        values,
        zeros if tension is None else tension,
        zeros if continuity is None else continuity,
        zeros if bias is None else bias,
    )
    sample_s = np.asarray(sample_s, dtype=np.float64)
    if k == 1:
        return np.broadcast_to(values[0], (sample_s.shape[0], values.shape[1])).copy()
    i = np.clip(np.searchsorted(times, sample_s, side="right") - 1, 0, k - 2)
    t0, t1 = times[i], times[i + 1]
    span = np.maximum(t1 - t0, 1e-9)
    s = np.clip((sample_s - t0) / span, 0.0, 1.0)[:, None]
    s2, s3 = s * s, s * s * s
    h00 = 2 * s3 - 3 * s2 + 1
    h10 = s3 - 2 * s2 + s
    h01 = -2 * s3 + 3 * s2
    h11 = s3 - s2
    span = span[:, None]
    out: np.ndarray = (
        h00 * values[i]
        + h10 * outgoing[i] * span
        + h01 * values[i + 1]
        + h11 * incoming[i + 1] * span
    )
    return out
