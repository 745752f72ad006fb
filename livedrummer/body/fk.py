"""Forward kinematics over many time samples at once.

Input: local joint rotations ``(T, N_JOINTS, 4)`` and the root position ``(T, 3)``; output:
world rotations and positions of every joint. The loop runs over the 24 joints in parent
order (fixed, short); every step is a numpy operation over all T samples, so sampling cost
per joint-pose is a few tens of nanoseconds. Leaf rotations are ignored (leaves are points).
"""

from __future__ import annotations

import numpy as np

from livedrummer.body import quat
from livedrummer.body.skeleton import N_JOINTS, PARENTS, Skeleton


def forward(
    skeleton: Skeleton, local: np.ndarray, root_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World quaternions ``(T, J, 4)`` and positions ``(T, J, 3)``."""
    lq = np.ascontiguousarray(np.moveaxis(local, 1, 0))  # (J, T, 4): one block per joint
    qs: list[np.ndarray] = [lq[0]]
    ps: list[np.ndarray] = [np.broadcast_to(root_m, (local.shape[0], 3))]
    for j in range(1, N_JOINTS):
        p = PARENTS[j]
        ps.append(ps[p] + quat.rotate(qs[p], skeleton.offsets[j]))
        qs.append(quat.mul(qs[p], lq[j]))
    world_q = np.stack(qs, axis=1)
    world_p = np.stack(ps, axis=1)
    return world_q, world_p


def to_local(world_q: np.ndarray) -> np.ndarray:
    """Local rotations from world rotations (inverse of the rotation half of :func:`forward`)."""
    local = world_q.copy()
    for j in range(1, N_JOINTS):
        local[..., j, :] = quat.relative(world_q[..., PARENTS[j], :], world_q[..., j, :])
    return local
