"""Where the performers stand: ChoreoGraphics' formations for drummers, pure numpy.

A formation is a shape, a density (how many performers) and a pattern (how they are spread on
the shape), as the ChoreoGraphics thesis specifies them, plus how they face and whether the
layout is mirrored. Our shapes are the ones drum lines and drum walls use:

* ``line``: side by side along x, ``spacing`` metres apart, centred on the stage's centre;
* ``arc``: on a circle of ``radius`` around a focus point behind the audience's view
  (``span_deg`` wide), so every drummer is the same distance from that point; neighbours are
  ``spacing`` apart at least (the radius grows when the span would put them closer);
* ``grid``: rows of ``columns``, ``spacing`` apart each way, the front row nearest the audience;
* ``v``: a wedge, the first performer at the apex nearest the audience, the others alternating
  left and right, each step back by ``spacing`` and out by ``spacing``;
* ``explicit``: the positions given, one per performer.

Coordinates are the renderer's: metres on the floor plane, z up; the audience sits on +y, so
a drummer facing the audience faces +y (yaw 0) and +x is that drummer's right (the audience's
left); yaw turns counter-clockwise seen from above, so yaw 90 faces -x. ``facing`` is ``audience``
(every yaw 0), ``center`` (each turned towards the formation's centre line, as a drum circle
plays to itself) or a number of degrees for all. ``symmetric`` (explicit positions only; the
other shapes are symmetric already) mirrors the positions given about x = 0: each one off the
mirror line gets a twin at -x, whose yaw is the mirror of its own, so half a layout is given
once.

Every shape but ``explicit`` keeps neighbours ``spacing`` apart, an ensemble's copies too;
whether that is room enough for the kits is :func:`livedrummer.stage.layout.check_footprints`'s
question, asked with the kits at hand.

Limits: a formation is fixed for the whole piece (no evolutions or trajectories between
formations).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

SHAPES = ("line", "arc", "grid", "v", "explicit")
FACINGS = ("audience", "center")


@dataclass(frozen=True)
class Placement:
    """One performer's spot: floor position (m) and yaw (degrees, 0 = facing the audience)."""

    x: float
    y: float
    yaw_deg: float = 0.0


@dataclass(frozen=True)
class Formation:
    shape: str = "line"
    spacing: float = 2.6  # m between neighbours (a five-piece kit is about 2 m wide)
    radius: float = 6.0  # arc
    span_deg: float = 120.0  # arc
    columns: int = 4  # grid
    facing: str | float = "audience"
    symmetric: bool = False
    positions: tuple[tuple[float, float], ...] = ()  # explicit

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"shape {self.shape!r}: expected one of {', '.join(SHAPES)}")
        if isinstance(self.facing, str) and self.facing not in FACINGS:
            raise ValueError(f"facing {self.facing!r}: expected audience, center or degrees")
        if self.spacing <= 0 or self.radius <= 0 or self.columns < 1:
            raise ValueError("spacing and radius must be > 0, columns >= 1")
        if self.symmetric and self.shape != "explicit":
            raise ValueError(
                f"symmetric: only for explicit positions ({self.shape} is symmetric already)"
            )


def place(formation: Formation, count: int) -> list[Placement]:
    """``count`` placements in ``formation`` (see the module docstring)."""
    if count < 1:
        raise ValueError("a formation needs at least one performer")
    f = formation
    if f.symmetric:
        points: list[tuple[float, float, bool]] = []
        for x, y in f.positions:
            points.append((float(x), float(y), False))
            if abs(x) > 1e-9:
                points.append((-float(x), float(y), True))
        if len(points) < count:
            raise ValueError(
                f"explicit symmetric formation: {len(points)} places for {count} performers"
            )
        points = points[:count]
    else:
        points = [(x, y, False) for x, y in _points(f, count)]
    cx = sum(p[0] for p in points) / len(points)
    cy = sum(p[1] for p in points) / len(points)
    return [Placement(x, y, _yaw(f, x - cx, y - cy, twin)) for x, y, twin in points]


def _points(f: Formation, n: int) -> list[tuple[float, float]]:
    if f.shape == "explicit":
        if len(f.positions) < n:
            raise ValueError(f"explicit formation: {len(f.positions)} positions for {n} performers")
        return [(float(x), float(y)) for x, y in f.positions[:n]]
    if f.shape == "line":
        return [((i - (n - 1) / 2) * f.spacing, 0.0) for i in range(n)]
    if f.shape == "grid":
        out = []
        for i in range(n):
            r, c = divmod(i, f.columns)
            in_row = min(f.columns, n - r * f.columns)
            out.append(((c - (in_row - 1) / 2) * f.spacing, -r * f.spacing))
        return out
    if f.shape == "v":
        out = [(0.0, 0.0)]
        for i in range(1, n):
            step = (i + 1) // 2
            side = 1.0 if i % 2 else -1.0
            out.append((side * step * f.spacing, -step * f.spacing))
        return out
    # arc: centred on a focus point in front (towards the audience); the arc's middle nearest
    span = math.radians(f.span_deg)
    if n > 1 and span <= 0.0:
        raise ValueError(f"arc span_deg 0 puts all {n} performers on one spot")
    angles = [0.0] if n == 1 else [(-span / 2 + span * i / (n - 1)) for i in range(n)]
    radius: float = f.radius
    if n > 1:
        arc_step = min(span / (n - 1), math.pi)
        radius = max(radius, f.spacing / (2.0 * math.sin(arc_step / 2.0)))
    return [(radius * math.sin(a), radius * (math.cos(a) - 1.0)) for a in angles]


def _yaw(f: Formation, dx: float, dy: float, twin: bool) -> float:
    if not isinstance(f.facing, str):
        return float(-f.facing if twin else f.facing)
    if f.facing == "audience":
        return 0.0
    if abs(dx) < 1e-9 and abs(dy) < 1e-9:
        return 0.0
    # facing (-sin yaw, cos yaw) must point at the centre, (-dx, -dy): yaw = atan2(dx, -dy)
    return math.degrees(math.atan2(dx, -dy))


def check_spacing(placements: Sequence[Placement], min_gap_m: float) -> None:
    """ValueError naming two performers closer than ``min_gap_m`` (their kits would collide)."""
    for i, a in enumerate(placements):
        for j in range(i + 1, len(placements)):
            b = placements[j]
            gap = math.hypot(a.x - b.x, a.y - b.y)
            if gap < min_gap_m:
                raise ValueError(
                    f"performers {i + 1} and {j + 1} stand {gap:.2f} m apart; "
                    f"their kits need {min_gap_m:.2f} m"
                )
