"""Linear blend skinning in numpy: the reference for the GPU vertex shader.

A pose gives every joint a world rotation (unit quaternion, w x y z) and a world position
(:func:`livedrummer.body.fk.forward`). :func:`joint_matrices` turns them into 4x4 matrices;
:func:`skin_matrices` multiplies each by the inverse of the joint's bind matrix
(:attr:`~livedrummer.avatar.model.SkinnedMesh.bind`); :func:`skin` blends a vertex's up to
four skin matrices by its weights. A vertex weighted fully to one joint therefore follows
that joint rigidly; the shader does the same sums in float32 and is tested against this.

Limits: linear blending (no dual quaternions), so a joint bent far thins its skin a little
(the "candy wrapper" of twisted forearms); the default character keeps twist on the bones
where it matters (wrists) small.
"""

from __future__ import annotations

import numpy as np

from livedrummer.avatar.model import SkinnedMesh


def joint_matrices(world_q: np.ndarray, world_p: np.ndarray) -> np.ndarray:
    """``(..., J, 4, 4)`` matrices (column vectors) from quaternions and positions."""
    q = np.asarray(world_q, np.float64)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.zeros((*q.shape[:-1], 4, 4))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    out[..., :3, 3] = world_p
    out[..., 3, 3] = 1.0
    return out


def skin_matrices(world: np.ndarray, bind: np.ndarray) -> np.ndarray:
    """``world[j] @ inverse(bind[j])`` for every joint, float32 (what the shader receives)."""
    return (np.asarray(world, np.float64) @ np.linalg.inv(np.asarray(bind, np.float64))).astype(
        np.float32
    )


def skin(mesh: SkinnedMesh, skin_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Skinned positions and (unnormalised-then-normalised) normals, float32 ``(V, 3)`` each."""
    m = np.einsum(
        "vk,vkij->vij", mesh.weights.astype(np.float64), skin_m.astype(np.float64)[mesh.joints]
    )
    p = np.einsum("vij,vj->vi", m[:, :3, :3], mesh.positions) + m[:, :3, 3]
    n = np.einsum("vij,vj->vi", m[:, :3, :3], mesh.normals)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    return p.astype(np.float32), n.astype(np.float32)
