"""The kit model: physical pieces in the drummer's seat frame, and the player's habits.

Frame: metres, origin on the floor under the centre of the throne, +x to the drummer's right,
+y forward (away from the drummer, towards the audience behind the kit), +z up. A piece's
``position_m`` is the centre of its playing surface (batter head or cymbal centre); its surface
normal leans ``tilt_deg`` away from straight up, towards azimuth ``facing_deg`` (0 = towards
the drummer, measured about +z so that positive turns towards the drummer's right). A kick's
batter head is vertical (tilt 90) and faces the drummer.

Player data lives with the pieces because it is a property of how this drummer plays *this*
kit: the preferred limb, the shortest interval one hand plays on it (Kragtwijk's
``minTimeGap``), its elasticity (how far the stick rebounds, 0..1) and the pair table
``pair(a, b)`` in [-1, 1] (+1: a with the right hand and b with the left; -1 the reverse;
0: no preference). ``pair`` is antisymmetric; it is stored once and negated on lookup.

A left-handed kit is the right-handed one mirrored through the x = 0 plane: positions and
facings are reflected, limbs swap sides and pair values change sign. Nothing is copied from a
file, so the two can never drift apart.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import TYPE_CHECKING

from livedrummer.errors import KitError
from livedrummer.kit.vocabulary import HiHat, Limb, PieceKind, Zone

if TYPE_CHECKING:  # numpy is imported where it is used: listing kits must not load it
    import numpy as np

    from livedrummer.kit.lights import LightSpec

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Piece:
    """One physical drum, cymbal or pedal-operated piece of the kit."""

    name: str
    kind: PieceKind
    position_m: Vec3
    radius_m: float
    depth_m: float
    tilt_deg: float
    facing_deg: float
    zones: tuple[Zone, ...]
    plays: tuple[str, ...]  # instrument roles (from note maps) this piece sounds
    preferred_limb: Limb
    min_time_gap_s: float
    elasticity: float
    pedal_position_m: Vec3 | None = None  # footboard, for kick and hi-hat
    double_pedal: bool = False
    swing_deg: float | None = None  # cymbals: largest swing at full velocity (None: by size)

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of the playing surface (pointing away from the shell, into the air)."""
        import numpy as np

        tilt = math.radians(self.tilt_deg)
        # Azimuth 0 points from the piece towards the seat (the -y side for a piece in front).
        to_seat = -np.asarray(self.position_m[:2], dtype=np.float64)
        norm = float(np.hypot(*to_seat))
        base = math.atan2(to_seat[1], to_seat[0]) if norm > 1e-9 else -math.pi / 2
        azimuth = base - math.radians(self.facing_deg)
        return np.array(
            [math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), math.cos(tilt)]
        )

    def mirrored(self) -> Piece:
        x, y, z = self.position_m
        pedal = self.pedal_position_m
        return replace(
            self,
            position_m=(-x, y, z),
            facing_deg=-self.facing_deg,
            preferred_limb=self.preferred_limb.mirrored,
            pedal_position_m=None if pedal is None else (-pedal[0], pedal[1], pedal[2]),
        )

    def limb_for(self, zone: Zone, hihat: HiHat = HiHat.NONE) -> Limb:
        """The limb a player prefers for this zone: the pedal zone of a hi-hat is a foot."""
        if self.kind is PieceKind.HIHAT and (zone is Zone.PEDAL or hihat is HiHat.PEDAL):
            return Limb.LF if self.preferred_limb in (Limb.RH, Limb.LF) else Limb.RF
        return self.preferred_limb


@dataclass(frozen=True)
class Kit:
    """A complete kit: pieces, seat height, and the pair preference table."""

    name: str
    description: str
    handedness: str  # "right" or "left"
    seat_height_m: float
    pieces: tuple[Piece, ...]
    pairs: Mapping[tuple[str, str], float] = field(default_factory=dict)
    source: str = "<memory>"
    lights: LightSpec | None = None  # the kit file's [lights] (livedrummer.kit.lights)
    _by_name: Mapping[str, Piece] = field(init=False, repr=False, compare=False)
    _routes: Mapping[str, Piece] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        by_name: dict[str, Piece] = {}
        routes: dict[str, Piece] = {}
        for piece in self.pieces:
            if piece.name in by_name:
                raise KitError(f"{self.source}: piece {piece.name!r} is defined twice")
            by_name[piece.name] = piece
            for role in piece.plays:
                if role in routes:
                    raise KitError(
                        f"{self.source}: instrument {role!r} is played by both "
                        f"{routes[role].name!r} and {piece.name!r}"
                    )
                routes[role] = piece
        object.__setattr__(self, "_by_name", MappingProxyType(by_name))
        object.__setattr__(self, "_routes", MappingProxyType(routes))
        object.__setattr__(self, "pairs", MappingProxyType(dict(self.pairs)))

    def piece(self, name: str) -> Piece:
        try:
            return self._by_name[name]
        except KeyError:
            raise KitError(f"kit {self.name!r} has no piece {name!r}") from None

    def resolve(self, instrument: str) -> Piece | None:
        """The piece that plays a note map's instrument role, or None if this kit has none."""
        return self._routes.get(instrument)

    def pair(self, a: str, b: str) -> float:
        """Kragtwijk's pair(a, b): +1 a right-handed and b left-handed, -1 the reverse."""
        if (a, b) in self.pairs:
            return self.pairs[(a, b)]
        if (b, a) in self.pairs:
            return -self.pairs[(b, a)]
        return 0.0

    def mirrored(self, name: str | None = None) -> Kit:
        """The same kit for a drummer of the other hand (see the module docstring)."""
        other = "left" if self.handedness == "right" else "right"
        return Kit(
            name=name or f"{self.name}-{other}",
            description=f"{self.description} (mirrored for a {other}-handed drummer)",
            handedness=other,
            seat_height_m=self.seat_height_m,
            pieces=tuple(p.mirrored() for p in self.pieces),
            pairs={key: -value for key, value in self.pairs.items()},
            source=f"{self.source} (mirrored)",
            lights=self.lights,
        )
