"""Two sets of pose records blended into one, every bone keeping its length.

Why this shape. The live synth cross-fades from its old curves to new ones after each rebuild
(:mod:`livedrummer.live.curves`) and a cued file render fades from one expression's animation
to the next (:mod:`livedrummer.render.cued`); both need the same blend, and it is pure body
math, so it lives here, below both. Rotations are interpolated by slerp
(:func:`~livedrummer.body.quat.slerp`), the root position linearly, and the joint positions are
rebuilt by forward kinematics from the blended rotations (a linear blend of positions would
shorten a bone whose two ends turn apart). The kit channels (swing, lift, glow) are blended
linearly. Limits: no stick guard is run on the blend (each side was guarded).
"""

from __future__ import annotations

import numpy as np

from livedrummer.body import fk, quat
from livedrummer.body.rig import Rig


def blend_rows(rig: Rig, a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Pose records ``a`` blended towards ``b`` by ``w`` (0: ``a``, 1: ``b``): rotations by
    slerp, positions by forward kinematics from them (the root linearly), channels linearly."""
    out = a.copy()
    wc = w.astype(np.float64)
    for name in ("swing", "lift", "glow"):
        shape = (-1,) + (1,) * (a[name].ndim - 1)
        out[name] = a[name] + (b[name] - a[name]) * wc.reshape(shape).astype(np.float32)
    q = quat.slerp(a["rotation"].astype(np.float64), b["rotation"].astype(np.float64), wc[:, None])
    pa = a["position"][:, 0].astype(np.float64)
    root = pa + (b["position"][:, 0].astype(np.float64) - pa) * wc[:, None]
    _, pos = fk.forward(rig.skeleton, q, root)
    out["rotation"] = q
    out["position"] = pos
    return out
