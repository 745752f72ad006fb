"""The pose record: one float32 structured array element per time sample.

This is the boundary format between motion and everything that shows it: the same bytes go
over ZeroMQ (one raw frame of N records) and into a GPU buffer, so every field is float32
and the layout is fixed by the joint list and the kit's piece count. Layout of one record
(``pose_dtype(P)``, packed, little-endian, no padding)::

    time_s    f4                 seconds on the performance clock
    rotation  f4[24][4]          local joint rotations, quaternions (w, x, y, z), JOINTS order
    position  f4[24][3]          world joint positions (m), kit frame (x right, y fwd, z up)
    swing     f4[P]              per piece: cymbal wobble / beater / footboard angle (rad)
    lift      f4[P]              per piece: hi-hat top cymbal height above closed (m)
    glow      f4[P]              per piece: hit highlight 0..1

``itemsize`` = 4 * (1 + 96 + 72 + 3P) bytes (708 bytes for a 10-piece kit). Joint order is
:data:`livedrummer.body.skeleton.JOINTS`; piece order is ``kit.pieces``.
"""

from __future__ import annotations

import numpy as np

from livedrummer.body.skeleton import N_JOINTS


def pose_dtype(n_pieces: int) -> np.dtype:
    return np.dtype(
        [
            ("time_s", "<f4"),
            ("rotation", "<f4", (N_JOINTS, 4)),
            ("position", "<f4", (N_JOINTS, 3)),
            ("swing", "<f4", (n_pieces,)),
            ("lift", "<f4", (n_pieces,)),
            ("glow", "<f4", (n_pieces,)),
        ]
    )


def pack_poses(
    times: np.ndarray,
    local_q: np.ndarray,
    world_p: np.ndarray,
    swing: np.ndarray,
    lift: np.ndarray,
    glow: np.ndarray,
) -> np.ndarray:
    out = np.empty(times.size, dtype=pose_dtype(swing.shape[1]))
    out["time_s"] = times
    out["rotation"] = local_q
    out["position"] = world_p
    out["swing"] = swing
    out["lift"] = lift
    out["glow"] = glow
    return out
