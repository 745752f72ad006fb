"""The live drummer's style: the expression it plays with, and how a change is eased in.

Why this shape. Offline, a performance is animated with one
:class:`~livedrummer.body.expression.Expression` (SMED's gains, shares and secondary-motion
amplitudes). Live, a show technician changes it while the drummer plays (a preset from a
cue, one parameter from a fader). Swapping the expression at once would re-animate the
window with bigger or smaller strokes and the cross-fade of the curves
(:mod:`livedrummer.live.curves`, at most ``blend_s`` and never past the next contact) would
have to absorb the whole difference in a few milliseconds: the joints would jump. So a
change is a *ramp* (:class:`StyleChange`): while it lasts, the synth animates its window
twice, with the old expression and with the new one, and each pose is the blend of the two
at its own time (:mod:`livedrummer.live.curves` blends them as it cross-fades: slerp, bones
kept), the new one's share rising over ``ramp_s`` seconds of performance time along a
smoothstep, so the ramp adds no speed at either end and every pose is a continuous function
of time. :class:`StyleRamp` holds the expression in force and the change under way.

A change that arrives mid-ramp starts a new ramp from the two expressions mixed field by
field (:func:`mix_expression`: linear; the shares too, which keeps their sum at one) at
that instant.

Limits: during a ramp each re-animation costs twice (two animations of the window); a
change mid-ramp starts from the field-wise mix, which is close to, not exactly, the blended
pose shown at that instant; the stroke model (``--strokes``) is chosen at start and not
ramped.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from livedrummer.body.expression import Expression


def mix_expression(a: Expression, b: Expression, w: float) -> Expression:
    """``a`` moved towards ``b`` by ``w`` (0: ``a``, 1: ``b``), field by field."""
    if w <= 0.0:
        return a
    if w >= 1.0:
        return b
    values: dict[str, object] = {}
    for f in fields(Expression):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, tuple):
            values[f.name] = tuple(float(p + (q - p) * w) for p, q in zip(x, y, strict=True))
        else:
            values[f.name] = float(x + (y - x) * w)
    return Expression(**values)  # type: ignore[arg-type]


@dataclass(frozen=True)
class StyleChange:
    """A change of expression under way: poses at performance times before ``start_s`` are
    played with ``old``, after ``start_s + length_s`` with ``new``, and in between they are a
    blend of the two with :meth:`weight`."""

    old: Expression
    new: Expression
    start_s: float
    length_s: float

    def weight(self, times: np.ndarray) -> np.ndarray:
        """The share of ``new`` at ``times`` (0..1, smoothstep: no speed added at either end)."""
        if self.length_s <= 0:
            return np.asarray(times >= self.start_s, dtype=np.float64)
        x = np.clip((np.asarray(times, dtype=np.float64) - self.start_s) / self.length_s, 0, 1)
        out: np.ndarray = x * x * (3.0 - 2.0 * x)
        return out

    def expression_at(self, t: float) -> Expression:
        """The two expressions mixed field by field at ``t`` (where a new change starts)."""
        return mix_expression(self.old, self.new, float(self.weight(np.array([t]))[0]))


class StyleRamp:
    """The expression in force, and the change under way (see the module docstring)."""

    def __init__(self, expression: Expression | None = None, ramp_s: float = 0.5) -> None:
        if ramp_s < 0:
            raise ValueError(f"need ramp_s >= 0 (got {ramp_s})")
        self.ramp_s = ramp_s
        self._to = expression or Expression()
        self._change: StyleChange | None = None
        self.changes = 0

    @property
    def target(self) -> Expression:
        """The expression the ramp is heading for (the one in force once it is over)."""
        return self._to

    def set(self, expression: Expression, now_s: float) -> None:
        """Ease into ``expression`` from clock (performance) time ``now_s`` on."""
        if expression == self._to:
            return
        old = self._change.expression_at(now_s) if self._change is not None else self._to
        self._change = StyleChange(old, expression, now_s, self.ramp_s)
        self._to = expression
        self.changes += 1

    def change(self, since_s: float) -> StyleChange | None:
        """The change that still shapes poses at performance times from ``since_s`` on (None
        once every such pose is played with :attr:`target` alone)."""
        c = self._change
        if c is not None and since_s > c.start_s + c.length_s:
            self._change = c = None
        return c
