"""Vectorized quaternion math on ``(..., 4)`` float arrays, stored ``(w, x, y, z)``.

Poses are sampled for thousands of times at once, so every function here takes arrays with
any leading shape and broadcasts; nothing loops in Python. Quaternions are kept unit length by
their producers (axis-angle, exp map, products of unit quaternions); :func:`normalize` is there
for callers that accumulate error. The log/exp pair maps rotations to rotation vectors and back:
stroke keyframes are interpolated as rotation vectors (a flat space where splines behave),
which is exact as long as a joint's rotation away from its rest stays below pi.
"""

from __future__ import annotations

import numpy as np

Array = np.ndarray


def identity(shape: tuple[int, ...] = ()) -> Array:
    q = np.zeros((*shape, 4))
    q[..., 0] = 1.0
    return q


def normalize(q: Array) -> Array:
    out: np.ndarray = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return out


def mul(a: Array, b: Array) -> Array:
    """Hamilton product a*b (apply b first, then a)."""
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def mul_x(q: Array, angle: Array) -> Array:
    """``q`` followed by a turn of ``angle`` about its own x axis: mul(q, about-x(angle))."""
    c = np.cos(0.5 * angle)
    s = np.sin(0.5 * angle)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(np.broadcast_shapes(q.shape, (*np.shape(angle), 4)))
    out[..., 0] = w * c - x * s
    out[..., 1] = w * s + x * c
    out[..., 2] = y * c + z * s
    out[..., 3] = z * c - y * s
    return out


def cross(a: Array, b: Array) -> Array:
    """Cross product over the last axis (cheaper than ``np.cross`` on many small calls)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(np.shape(a), np.shape(b)))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def conj(q: Array) -> Array:
    out: np.ndarray = q * np.array([1.0, -1.0, -1.0, -1.0])
    return out


def relative(parent: Array, q: Array) -> Array:
    """World rotation ``q`` in the frame of world rotation ``parent`` (world to local):
    ``mul(parent, relative(parent, q)) == q``. The one world-to-local step of the body
    (:func:`~livedrummer.body.fk.to_local`, :func:`~livedrummer.body.strike.to_local`)."""
    return mul(conj(parent), q)


def rotate(q: Array, v: Array) -> Array:
    """Rotate vectors ``v`` (..., 3) by unit quaternions ``q`` (..., 4)."""
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * cross(u, v)
    out: np.ndarray = v + w * t + cross(u, t)
    return out


def from_axis_angle(axis: Array, angle: Array | float) -> Array:
    axis = np.asarray(axis, dtype=np.float64)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    n = axis / np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-300)
    shape = np.broadcast_shapes(half.shape[:-1], n.shape[:-1])
    half = np.broadcast_to(half, (*shape, 1))
    n = np.broadcast_to(n, (*shape, 3))
    return np.concatenate([np.cos(half), np.sin(half) * n], axis=-1)


def exp(rv: Array) -> Array:
    """Rotation vector (axis * angle) to unit quaternion."""
    rv = np.asarray(rv, dtype=np.float64)
    angle = np.linalg.norm(rv, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(half)/angle, with its limit 1/2 at zero
    k = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-300), 0.5 - angle**2 / 48.0)
    return np.concatenate([np.cos(half), k * rv], axis=-1)


def log(q: Array) -> Array:
    """Unit quaternion to rotation vector, choosing the rotation of angle <= pi."""
    q = np.where(q[..., :1] < 0.0, -q, q)
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., :1])
    k = np.where(s > 1e-12, angle / np.maximum(s, 1e-300), 2.0)
    out: np.ndarray = k * q[..., 1:]
    return out


def slerp(a: Array, b: Array, w: Array | float) -> Array:
    """Spherical interpolation from unit ``a`` (w = 0) to unit ``b`` (w = 1) along the shorter
    arc, at constant angular speed; ``w`` broadcasts over the leading axes. Near-equal
    rotations (under 1e-6 rad apart) are interpolated linearly and normalised."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)[..., None]
    d = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(d < 0.0, -b, b)
    d = np.clip(np.abs(d), 0.0, 1.0)
    theta = np.arccos(d)
    s = np.sin(theta)
    small = s < 1e-6
    safe = np.where(small, 1.0, s)
    ka = np.where(small, 1.0 - w, np.sin((1.0 - w) * theta) / safe)
    kb = np.where(small, w, np.sin(w * theta) / safe)
    return normalize(ka * a + kb * b)


def between(a: Array, b: Array) -> Array:
    """Shortest rotation taking unit vectors ``a`` onto unit vectors ``b``."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    d = np.sum(a * b, axis=-1, keepdims=True)
    c = cross(a, b)
    q = np.concatenate([1.0 + d, c], axis=-1)
    # antiparallel: any axis perpendicular to a
    anti = (1.0 + d)[..., 0] < 1e-9
    if np.any(anti):
        perp = np.cross(a, np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(perp, axis=-1) < 1e-6
        perp = np.where(small[..., None], np.cross(a, np.array([0.0, 1.0, 0.0])), perp)
        q = np.where(anti[..., None], np.concatenate([np.zeros_like(d), perp], axis=-1), q)
    return normalize(q)


def from_matrix(m: Array) -> Array:
    """Rotation matrices (..., 3, 3) (columns = rotated basis vectors) to quaternions."""
    m = np.asarray(m, dtype=np.float64)
    tr = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    cands = np.stack(
        [
            np.stack(
                [
                    1 + tr,
                    m[..., 2, 1] - m[..., 1, 2],
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 1, 0] - m[..., 0, 1],
                ],
                axis=-1,
            ),
            np.stack(
                [
                    m[..., 2, 1] - m[..., 1, 2],
                    1 + m[..., 0, 0] - m[..., 1, 1] - m[..., 2, 2],
                    m[..., 0, 1] + m[..., 1, 0],
                    m[..., 0, 2] + m[..., 2, 0],
                ],
                axis=-1,
            ),
            np.stack(
                [
                    m[..., 0, 2] - m[..., 2, 0],
                    m[..., 0, 1] + m[..., 1, 0],
                    1 - m[..., 0, 0] + m[..., 1, 1] - m[..., 2, 2],
                    m[..., 1, 2] + m[..., 2, 1],
                ],
                axis=-1,
            ),
            np.stack(
                [
                    m[..., 1, 0] - m[..., 0, 1],
                    m[..., 0, 2] + m[..., 2, 0],
                    m[..., 1, 2] + m[..., 2, 1],
                    1 - m[..., 0, 0] - m[..., 1, 1] + m[..., 2, 2],
                ],
                axis=-1,
            ),
        ],
        axis=-2,
    )
    norms = np.linalg.norm(cands, axis=-1)
    best = np.argmax(norms, axis=-1)
    q = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    q = normalize(q)
    return np.where(q[..., :1] < 0.0, -q, q)


def to_matrix(q: Array) -> Array:
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def _basis_q(direction: Array, side: Array) -> Array:
    """Quaternion of the frame with columns (d, s, d x s) built from a direction and a side
    hint, computed from the columns without forming the matrix (the hot path of the IK)."""
    d = direction / np.linalg.norm(direction, axis=-1, keepdims=True)
    s = side - np.sum(side * d, axis=-1, keepdims=True) * d
    s = s / np.maximum(np.linalg.norm(s, axis=-1, keepdims=True), 1e-12)
    c = cross(d, s)
    m00, m10, m20 = d[..., 0], d[..., 1], d[..., 2]
    m01, m11, m21 = s[..., 0], s[..., 1], s[..., 2]
    m02, m12, m22 = c[..., 0], c[..., 1], c[..., 2]
    out = np.empty((*np.shape(m00), 4))
    out[..., 0] = 0.5 * np.sqrt(np.maximum(0.0, 1.0 + m00 + m11 + m22))
    out[..., 1] = np.copysign(0.5 * np.sqrt(np.maximum(0.0, 1.0 + m00 - m11 - m22)), m21 - m12)
    out[..., 2] = np.copysign(0.5 * np.sqrt(np.maximum(0.0, 1.0 - m00 + m11 - m22)), m02 - m20)
    out[..., 3] = np.copysign(0.5 * np.sqrt(np.maximum(0.0, 1.0 - m00 - m11 + m22)), m10 - m01)
    return normalize(out)


def align(rest_dir: Array, rest_side: Array, direction: Array, side: Array) -> Array:
    """The rotation taking ``rest_dir`` onto ``direction`` and the plane (rest_dir, rest_side)
    onto the plane (direction, side): how a bone is aimed and twisted from its rest pose."""
    rd = np.asarray(rest_dir, dtype=np.float64)
    rs = np.asarray(rest_side, dtype=np.float64)
    if rd.ndim == 1 and rs.ndim == 1:  # a constant rest frame (every caller): built once
        key = rd.tobytes() + rs.tobytes()
        inv = _REST.get(key)
        if inv is None:
            inv = _REST[key] = conj(_basis_q(rd, rs))
    else:
        inv = conj(_basis_q(rd, rs))
    return mul(_basis_q(direction, side), inv)


_REST: dict[bytes, Array] = {}
