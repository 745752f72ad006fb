"""Fitting an avatar to a kit: scale the avatar, or move the kit to the avatar (``--fit``).

Why this shape. A kit file is measured for one body, the default drummer of
:class:`~livedrummer.body.skeleton.SegmentLengths` (1.78 m); avatars come at every scale (a
VRoid model of 0.66 m, a giant of 2.5 m). Two ways make them meet:

* ``avatar``: the avatar is scaled about the floor under its hips (mesh, bind matrices and
  proportions, the stick excepted: a prop keeps its 0.30 m) so that its *reach* (arm, leg and
  back: the three ratios to the default body's, averaged) is the reach the kit is built for.
  Reach, not height, because a big-headed avatar scaled to 1.78 m would still be short of arm;
* ``kit``: the throne height and every piece's position and footboard are scaled about the
  floor under the throne by the avatar's reach ratio. Pieces keep their size (stands and
  pedals move; a drum does not shrink), so this suits avatars near the kit's body: far from
  it, rack toms would crowd into one another, so it is refused beyond :data:`KIT_LIMIT`.

``auto`` (the default) leaves an avatar that reaches the kit alone (``none``), moves the kit
when the avatar's reach is within :data:`KIT_RANGE` of the kit's body, and else scales the
avatar; whichever is chosen is verified by building the rig (the same reach check every
command makes), and if it fails the other way is tried. :func:`fit_avatar` is the one code
path: ``avatar info`` reports its verdict, ``render``/``check``/``export``/``synth``/``display``
play what it returns, so the two cannot disagree. Limits: a uniform scale (proportions are
the avatar's own); the kit is moved as a whole, not piece by piece.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.body.rig import Rig, build_rig
from livedrummer.body.skeleton import J, SegmentLengths
from livedrummer.errors import UnreachableError
from livedrummer.kit.model import Kit

FITS = ("auto", "avatar", "kit", "none")
#: Reach ratios (avatar / kit's body) for which ``auto`` moves the kit rather than the avatar.
KIT_RANGE = (0.85, 1.2)
#: Reach ratios beyond which the kit is not moved at all: its pieces, keeping their size,
#: would crowd into one another (at x0.35 the sticks miss by 0.1 m) or stand apart.
KIT_LIMIT = (0.7, 1.5)
#: Factors on the first scale tried when it still leaves a piece out of reach.
RETRY = (1.05, 0.95, 1.1, 0.9, 1.15, 1.2)
_BODY = SegmentLengths()


@dataclass(frozen=True)
class Fitting:
    """What :func:`fit_avatar` settled: the kit and avatar to play, and the line that says so."""

    kit: Kit
    avatar: Avatar | None
    rig: Rig
    asked: str  # the --fit given
    mode: str  # "none", "avatar" or "kit": what was done
    scale: float  # the avatar's (mode avatar) or the kit's (mode kit) factor; 1 for none
    reach: float  # the avatar's reach as a ratio of the kit's body's
    line: str  # one sentence: which and why

    def as_json(self) -> dict[str, object]:
        return {"asked": self.asked, "mode": self.mode, "scale": round(self.scale, 4),
                "reach_ratio": round(self.reach, 4), "kit": self.kit.name,
                "said": self.line}  # fmt: skip


def reach_ratio(lengths: SegmentLengths) -> float:
    """The avatar's arm, leg and back as ratios to the default body's, averaged."""
    s, d = lengths, _BODY
    arm = (s.upper_arm + s.forearm + s.hand) / (d.upper_arm + d.forearm + d.hand)
    leg = (s.thigh + s.shin) / (d.thigh + d.shin)
    back = (s.pelvis_height + s.lower_back + s.upper_back + s.chest_to_shoulder) / (
        d.pelvis_height + d.lower_back + d.upper_back + d.chest_to_shoulder
    )
    return float((arm + leg + back) / 3.0)


def height_m(avatar: Avatar) -> float:
    z = avatar.mesh.positions[:, 2]
    return float(z.max() - z.min())


def scaled_lengths(lengths: SegmentLengths, k: float) -> SegmentLengths:
    """Every segment times ``k`` but the stick (a prop)."""
    values = {f: getattr(lengths, f) * k for f in lengths.__dataclass_fields__ if f != "stick"}
    return replace(lengths, **values)


def scaled_avatar(avatar: Avatar, k: float) -> Avatar:
    """``avatar`` scaled by ``k`` about the floor under its hips (the loader's origin)."""
    mesh = avatar.mesh
    bind = mesh.bind.copy()
    bind[:, :3, 3] *= np.float32(k)
    for side in ("r", "l"):  # the stick keeps its length: the tip stays as far from the grip
        stick, tip = J[f"{side}_stick"], J[f"{side}_tip"]
        bind[tip, :3, 3] = bind[stick, :3, 3] + (mesh.bind[tip, :3, 3] - mesh.bind[stick, :3, 3])
    new_mesh = replace(
        mesh, positions=(mesh.positions * np.float32(k)).astype(np.float32), bind=bind
    )
    faces = {
        name: replace(f, deltas=(f.deltas * np.float32(k)).astype(np.float32))
        for name, f in avatar.faces.items()
    }
    return Avatar(
        avatar.name,
        avatar.source,
        scaled_lengths(avatar.lengths, k),
        new_mesh,
        dict(avatar.bones),
        faces=faces,
    )


def moved_kit(kit: Kit, k: float) -> Kit:
    """``kit`` with its throne height, piece positions and footboards scaled by ``k`` about
    the floor under the throne (sizes kept)."""

    def times(v: tuple[float, float, float]) -> tuple[float, float, float]:
        return (v[0] * k, v[1] * k, v[2] * k)

    pieces = tuple(
        replace(
            p,
            position_m=times(p.position_m),
            pedal_position_m=None if p.pedal_position_m is None else times(p.pedal_position_m),
        )
        for p in kit.pieces
    )
    return Kit(
        kit.name,
        kit.description,
        kit.handedness,
        kit.seat_height_m * k,
        pieces,
        dict(kit.pairs),
        f"{kit.source} (moved x{k:.3f} to the avatar)",
        kit.lights,
    )


def _try(kit: Kit, lengths: SegmentLengths | None) -> tuple[Rig | None, str]:
    try:
        return build_rig(kit, lengths), ""
    except UnreachableError as exc:
        return None, str(exc)


def _by_avatar(kit: Kit, avatar: Avatar, reach: float) -> tuple[Fitting | None, str]:
    first = 1.0 / reach
    error = ""
    for k in (first, *(first * r for r in RETRY)):
        big = scaled_avatar(avatar, k)
        rig, error = _try(kit, big.lengths)
        if rig is not None:
            line = (
                f"avatar scaled x{k:.3f} ({height_m(avatar):.2f} m -> {height_m(big):.2f} m): "
                f"its reach is x{reach:.2f} of the body kit {kit.name} is built for"
            )
            return Fitting(kit, big, rig, "", "avatar", k, reach, line), ""
    return None, error


def _by_kit(kit: Kit, avatar: Avatar, reach: float) -> tuple[Fitting | None, str]:
    if not KIT_LIMIT[0] <= reach <= KIT_LIMIT[1]:
        return None, (
            f"{kit.source}: the avatar's reach is x{reach:.2f} of the body the kit "
            f"is built for, beyond the x{KIT_LIMIT[0]:.2f}..x{KIT_LIMIT[1]:.2f} a kit "
            "can be moved (its pieces keep their size; --fit avatar scales the avatar)"
        )
    error = ""
    for k in (reach, *(reach * r for r in RETRY)):
        moved = moved_kit(kit, k)
        rig, error = _try(moved, avatar.lengths)
        if rig is not None:
            line = (
                f"kit {kit.name} moved to the avatar: throne {kit.seat_height_m:.2f} -> "
                f"{moved.seat_height_m:.2f} m, pedals and stands x{k:.3f} (its reach is "
                f"x{reach:.2f} of the body the kit is built for; the pieces keep their size)"
            )
            return Fitting(moved, avatar, rig, "", "kit", k, reach, line), ""
    return None, error


_Way = Callable[[Kit, Avatar, float], tuple[Fitting | None, str]]


def fit_avatar(kit: Kit, avatar: Avatar | None, asked: str = "auto") -> Fitting:
    """The kit and avatar to play (see the module docstring); raises
    :class:`~livedrummer.errors.UnreachableError` (one line, naming the avatar and ``--fit``)
    when the way asked for leaves a piece out of reach."""
    if asked not in FITS:
        raise ValueError(f"--fit must be one of {', '.join(FITS)}, got {asked!r}")
    if avatar is None:
        rig, error = _try(kit, None)
        if rig is None:
            raise UnreachableError(error)
        return Fitting(
            kit,
            None,
            rig,
            asked,
            "none",
            1.0,
            1.0,
            f"the built-in character: kit {kit.name} is built for it",
        )
    reach = reach_ratio(avatar.lengths)
    who = f"with avatar {avatar.source}"
    if asked in ("auto", "none"):
        rig, error = _try(kit, avatar.lengths)
        if rig is not None:
            line = (
                f"avatar as it is ({height_m(avatar):.2f} m): it reaches every piece of "
                f"kit {kit.name} (reach x{reach:.2f} of the kit's body)"
            )
            return Fitting(kit, avatar, rig, asked, "none", 1.0, reach, line)
        if asked == "none":
            hint = ""
            try:
                other = fit_avatar(kit, avatar, "auto")
                hint = f"; --fit auto would fit it: {other.mode} x{other.scale:.3f}"
            except UnreachableError:
                pass
            raise UnreachableError(f"{error}, {who} (--fit none{hint})")
    order: list[_Way]
    if asked == "auto":
        near = KIT_RANGE[0] <= reach <= KIT_RANGE[1]
        order = [_by_kit, _by_avatar] if near else [_by_avatar, _by_kit]
    else:
        order = [_by_kit] if asked == "kit" else [_by_avatar]
    errors = []
    for way in order:
        done, error = way(kit, avatar, reach)
        if done is not None:
            why = "" if asked != "auto" else " (--fit auto: it does not reach the kit as it is)"
            return replace(done, asked=asked, line=done.line + why)
        errors.append(error)
    raise UnreachableError(f"{errors[-1]}, {who} (--fit {asked} could not fit it)")
