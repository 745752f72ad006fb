"""BVH export: the skeleton's hierarchy and its motion, readable by Blender, MotionBuilder...

BVH is Y-up by convention, so the kit frame (x right, y forward, z up) is turned into
(x right, y up, z backwards) by ``M = [[1,0,0],[0,0,1],[0,-1,0]]`` (a proper rotation) and
metres become centimetres. Every rotating joint gets ``Zrotation Xrotation Yrotation``
channels (the common order; the rotation is ``Rz @ Rx @ Ry`` in the parent's frame) and the
root also its position. Leaf joints (stick tips, toes, top of the head) are End Sites. The
text is produced by :func:`bvh_text` from arrays (no I/O); the CLI writes it.

Limits: Euler angles pass through gimbal lock when a joint's X rotation reaches +-90
degrees; the positions stay right, only the angle curves jump.
"""

from __future__ import annotations

import numpy as np

from livedrummer.body import quat
from livedrummer.body.skeleton import JOINTS, LEAVES, N_JOINTS, PARENTS, Skeleton

M = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
CM = 100.0


def _children(j: int) -> list[int]:
    return [k for k in range(N_JOINTS) if PARENTS[k] == j]


def joint_order() -> list[int]:
    """Rotating joints in the depth-first order their channels appear in a motion line."""
    order: list[int] = []

    def visit(j: int) -> None:
        order.append(j)
        for k in _children(j):
            if k not in LEAVES:
                visit(k)

    visit(0)
    return order


def euler_zxy_deg(q: np.ndarray) -> np.ndarray:
    """(..., 4) kit-frame quaternions -> (..., 3) BVH-frame Z, X, Y angles in degrees."""
    r = M @ quat.to_matrix(q) @ M.T
    x = np.arcsin(np.clip(r[..., 2, 1], -1.0, 1.0))
    z = np.arctan2(-r[..., 0, 1], r[..., 1, 1])
    y = np.arctan2(-r[..., 2, 0], r[..., 2, 2])
    out: np.ndarray = np.degrees(np.stack([z, x, y], axis=-1))
    return out


def _fmt(values: np.ndarray) -> str:
    return " ".join(f"{v:.6f}" for v in values)


def hierarchy_text(skeleton: Skeleton) -> str:
    lines: list[str] = ["HIERARCHY"]

    def visit(j: int, depth: int) -> None:
        pad = "\t" * depth
        if j == 0:
            lines.append(f"ROOT {JOINTS[j]}")
        else:
            lines.append(f"{pad}JOINT {JOINTS[j]}")
        lines.append(pad + "{")
        offset = np.zeros(3) if j == 0 else M @ skeleton.offsets[j] * CM
        lines.append(f"{pad}\tOFFSET {_fmt(offset)}")
        if j == 0:
            lines.append(
                f"{pad}\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
            )
        else:
            lines.append(f"{pad}\tCHANNELS 3 Zrotation Xrotation Yrotation")
        for k in _children(j):
            if k in LEAVES:
                lines.append(f"{pad}\tEnd Site")
                lines.append(pad + "\t{")
                lines.append(f"{pad}\t\tOFFSET {_fmt(M @ skeleton.offsets[k] * CM)}")
                lines.append(pad + "\t}")
            else:
                visit(k, depth + 1)
        lines.append(pad + "}")

    visit(0, 0)
    return "\n".join(lines) + "\n"


def motion_text(local_q: np.ndarray, root_m: np.ndarray, fps: float) -> str:
    """MOTION section for local rotations (T, J, 4) and root positions (T, 3)."""
    order = joint_order()
    angles = euler_zxy_deg(local_q[:, order])  # (T, len(order), 3)
    root = root_m @ M.T * CM
    rows = np.concatenate([root, angles.reshape(angles.shape[0], -1)], axis=1)
    body = "\n".join(_fmt(row) for row in rows)
    return f"MOTION\nFrames: {rows.shape[0]}\nFrame Time: {1.0 / fps:.8f}\n{body}\n"


def bvh_text(skeleton: Skeleton, local_q: np.ndarray, root_m: np.ndarray, fps: float) -> str:
    return hierarchy_text(skeleton) + motion_text(local_q, root_m, fps)
