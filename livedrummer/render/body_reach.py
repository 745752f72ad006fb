"""Boxes round the drawn drummer for a frame, pure numpy: what a shadow region needs.

:class:`SkinBoxes` skins a skinned avatar's vertices on the CPU with the frame's skin matrices
(the same linear blend as ``shaders/skin.vert``, about 2 ms for 6,000 vertices) and boxes them
per dominant joint: tight boxes, one per body part. :class:`BodyReach` boxes the capsule
mannequin from the joints alone: one group per drawn segment (its two joints, its radius) and
per ball. The union of the boxes holds everything drawn of the drummer
(:mod:`livedrummer.render.shadow_region`). Limits: face shapes move vertices off their bind
positions by a few centimetres, which :class:`SkinBoxes` does not skin; the caller adds a
margin for them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


class SkinBoxes:
    """A skinned mesh's vertices boxed per dominant joint for a pose's skin matrices."""

    def __init__(self, positions: np.ndarray, joints: np.ndarray, weights: np.ndarray) -> None:
        idx = np.asarray(joints).astype(np.int64)
        w = np.asarray(weights, np.float32)
        w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-12)  # as skin.vert renormalises
        dominant = idx[np.arange(len(idx)), w.argmax(axis=1)]
        order = np.argsort(dominant, kind="stable")
        self._pos = np.c_[positions, np.ones(len(positions))].astype(np.float32)[order]
        self._joints, self._weights = idx[order], w[order]
        ranked = dominant[order]
        self._starts = np.flatnonzero(np.r_[True, ranked[1:] != ranked[:-1]])

    def boxes(self, skin_m: np.ndarray, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Per dominant joint the box (lo (G, 3), hi (G, 3)) of the vertices skinned by
        ``skin_m`` (J, 4, 4), grown by ``margin_m``."""
        if not len(self._pos):
            return np.zeros((0, 3)), np.zeros((0, 3))
        m = np.asarray(skin_m, np.float32)[:, :3, :]
        out = np.zeros((len(self._pos), 3), np.float32)
        for k in range(self._joints.shape[1]):
            moved = np.einsum("vij,vj->vi", m[self._joints[:, k]], self._pos)
            out += self._weights[:, k : k + 1] * moved
        lo = np.minimum.reduceat(out, self._starts, axis=0) - margin_m
        hi = np.maximum.reduceat(out, self._starts, axis=0) + margin_m
        return lo.astype(np.float64), hi.astype(np.float64)


@dataclass(frozen=True)
class BodyReach:
    """Groups of (joint, radius) pairs: ``group`` (P,) sorted, ``joint`` (P,), ``radius_m`` (P,)."""

    group: np.ndarray
    joint: np.ndarray
    radius_m: np.ndarray

    @classmethod
    def from_capsules(
        cls,
        parent: np.ndarray,
        bones: np.ndarray,
        bone_radius_m: np.ndarray,
        balls: np.ndarray,
        ball_radius_m: np.ndarray,
    ) -> BodyReach:
        """From the mannequin: segments from ``parent[bones]`` to ``bones`` of their radii, and
        balls at joints ``balls``."""
        nb = len(bones)
        g = np.r_[np.repeat(np.arange(nb), 2), nb + np.arange(len(balls))]
        j = np.r_[np.column_stack([parent[bones], bones]).reshape(-1), balls]
        r = np.r_[np.repeat(bone_radius_m, 2), ball_radius_m]
        return cls(g.astype(np.int64), j.astype(np.int64), r.astype(np.float64))

    def boxes(self, joints_m: np.ndarray, margin_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Each group's box (lo (G, 3), hi (G, 3)) for a frame's joint positions (J, 3), grown
        by ``margin_m``."""
        if not len(self.group):
            return np.zeros((0, 3)), np.zeros((0, 3))
        p = np.asarray(joints_m, np.float64)[self.joint]
        reach = (self.radius_m + margin_m)[:, None]
        starts = np.flatnonzero(np.r_[True, self.group[1:] != self.group[:-1]])
        return (
            np.minimum.reduceat(p - reach, starts, axis=0),
            np.maximum.reduceat(p + reach, starts, axis=0),
        )
