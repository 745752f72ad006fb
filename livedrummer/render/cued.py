"""A file performance whose style changes at cues: the body animated once per expression in
force, the poses blended from one to the next over ``ramp_s`` after each cue.

Why this shape. The body animates a whole performance with one expression
(:func:`~livedrummer.body.animation.animate`); a cue list (:mod:`livedrummer.live.cues`)
changes it at given times. Rather than animate each section on its own (its strokes would
start cold at the section's edge), the whole performance is animated with each expression a
cue brings, and each pose is blended from the expression before a cue to the one after it
along the same smoothstep ramp the live synth uses (:mod:`livedrummer.live.style`), with the
same slerp blend (:func:`~livedrummer.body.blend.blend_rows`).

Limits: one animation of the whole performance per style cue (each about what a plain
render's animation costs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body.blend import blend_rows
from livedrummer.body.perform import Performed
from livedrummer.body.sample import sample_poses
from livedrummer.render.body_scene import BodyScene


def _sample(p: Performed, times: np.ndarray) -> np.ndarray:
    return sample_poses(p.animation, p.sticking, times, p.chokes)


@dataclass(frozen=True)
class CuedBodyScene(BodyScene):
    """``performed`` is the performance before the first cue; ``styled`` holds (cue time,
    the performance animated with the expression from then on), by time."""

    styled: tuple[tuple[float, Performed], ...] = ()
    ramp_s: float = 0.5

    def poses(self, times: np.ndarray) -> np.ndarray:
        times = np.asarray(times, np.float64)
        out = _sample(self.performed, times)
        rig = self.performed.animation.rig
        for at, performed in self.styled:
            x = (
                np.clip((times - at) / self.ramp_s, 0.0, 1.0)
                if self.ramp_s > 0
                else ((times >= at).astype(np.float64))
            )
            w = x * x * (3.0 - 2.0 * x)
            mixed = w > 0
            if mixed.any():
                out[mixed] = blend_rows(rig, out[mixed], _sample(performed, times[mixed]), w[mixed])
        return out
