"""Loading kits from TOML files, strictly, and finding them by name.

File layout (every key is checked; unknown keys are errors naming file, table and key)::

    [kit]
    name = "rock5"
    description = "..."
    handedness = "right"          # "right" or "left"
    seat_height_m = 0.52

    [[piece]]
    name = "snare"
    kind = "snare"                # see livedrummer.kit.vocabulary.PieceKind
    position_m = [-0.05, 0.35, 0.65]
    radius_m = 0.178
    depth_m = 0.14
    tilt_deg = 8.0                # surface normal leans this far from vertical ...
    facing_deg = 0.0              # ... towards the drummer (0) or turned by this azimuth
    zones = ["head", "rim", "cross_stick"]   # optional; defaults by kind
    plays = ["snare"]             # optional; defaults to [name]
    preferred_limb = "LH"
    min_time_gap_s = 0.10
    elasticity = 0.8
    pedal_position_m = [...]      # kick and hi-hat only (required there)
    double_pedal = false          # kick only
    swing_deg = 7.0               # cymbals only, optional: largest swing (default by diameter)

    [[pair]]
    pieces = ["ride", "hihat"]    # pair(ride, hihat) ...
    value = 1.0                   # ... = +1: ride right hand, hi-hat left hand

Extensions. ``KIT+EXT`` (``rock5+percussion``) is kit KIT with the pieces of
``kits/extensions/EXT.toml`` added: a ``[extension]`` table (``name``, ``description``, the
``handedness`` its positions are for) and ``[[piece]]`` tables as above. Like ``-left``, an
extended kit is derived when it is named, never copied into a file; the extension's pieces are
mirrored when the kit is of the other hand, and a piece name the kit already has is an error.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import replace
from pathlib import Path

from livedrummer.config import Table, read_toml
from livedrummer.errors import KitError
from livedrummer.kit.catalog import entries, looks_like_path
from livedrummer.kit.lights import parse_light_spec
from livedrummer.kit.model import Kit, Piece
from livedrummer.kit.vocabulary import DEFAULT_ZONES, INSTRUMENTS, Limb, PieceKind, Zone

_MIRROR_SUFFIX = {"-left": "left", "-right": "right"}
_MAX_REACH_M = 3.0  # no piece of a playable kit is further than this from the seat
_FLOOR_TOLERANCE_M = 0.01  # a rim or footboard may touch the floor (z = 0), not sink into it


def parse_kit(data: dict[str, object], source: str) -> Kit:
    """Build a :class:`Kit` from parsed TOML, checking every key and value."""
    root = Table(data, source, "", KitError)
    head = root.table("kit")
    name = head.text("name")
    kit_kwargs = {
        "name": name,
        "description": head.text("description", ""),
        "handedness": head.text("handedness", "right", choices=("right", "left")),
        "seat_height_m": head.number("seat_height_m", 0.52, lo=0.2, hi=1.2),
    }
    head.done()
    piece_tables = root.tables("piece", label="name")
    if not piece_tables:
        raise root.fail("piece", "a kit needs at least one [[piece]]")
    pieces = tuple(_parse_piece(t) for t in piece_tables)
    names: set[str] = set()
    for piece, t in zip(pieces, piece_tables, strict=True):
        if piece.name in names:
            raise t.fail("name", "another piece has this name", piece.name)
        names.add(piece.name)
    pairs: dict[tuple[str, str], float] = {}
    for t in root.tables("pair"):
        a, b = _pair_names(t, names)
        value = t.number("value", lo=-1.0, hi=1.0)
        if (a, b) in pairs or (b, a) in pairs:
            raise t.fail("pieces", "this pair is already defined", [a, b])
        pairs[(a, b)] = value
        t.done()
    lights = parse_light_spec(root.table("lights")) if root.has("lights") else None
    root.done()
    return Kit(pieces=pieces, pairs=pairs, source=source, lights=lights, **kit_kwargs)


def _pair_names(t: Table, names: set[str]) -> tuple[str, str]:
    pair = t.texts("pieces")
    if len(pair) != 2 or pair[0] == pair[1]:
        raise t.fail("pieces", "expected two different piece names", list(pair))
    for n in pair:
        if n not in names:
            raise t.fail("pieces", f"no piece named {n!r} in this kit", list(pair))
    return pair[0], pair[1]


def _parse_piece(t: Table) -> Piece:
    name = t.text("name")
    if not name.strip():
        raise t.fail("name", "a piece needs a name", name)
    kind = PieceKind(t.text("kind", choices=[k.value for k in PieceKind]))
    position = t.vector("position_m", 3)
    if sum(c * c for c in position) ** 0.5 > _MAX_REACH_M:
        raise t.fail("position_m", f"is more than {_MAX_REACH_M} m from the seat", list(position))
    zone_names = [z.value for z in DEFAULT_ZONES[kind]]
    allowed = zone_names + (["bell"] if kind is PieceKind.HIHAT else [])
    zones = tuple(Zone(z) for z in _choices(t, "zones", allowed, zone_names))
    plays = _choices(t, "plays", list(INSTRUMENTS), [name] if name in INSTRUMENTS else [])
    needs_pedal = kind in (PieceKind.KICK, PieceKind.HIHAT)
    pedal = t.vector("pedal_position_m", 3) if needs_pedal else None
    double = t.boolean("double_pedal", False) if kind is PieceKind.KICK else False
    swing = t.number("swing_deg", None, lo=0.0, hi=30.0) if kind.is_cymbal else None
    piece = Piece(
        name=name,
        kind=kind,
        position_m=position,
        radius_m=t.number("radius_m", lo=0.03, hi=0.6),
        depth_m=t.number("depth_m", 0.0, lo=0.0, hi=0.8),
        tilt_deg=t.number("tilt_deg", 0.0, lo=0.0, hi=90.0),
        facing_deg=t.number("facing_deg", 0.0, lo=-180.0, hi=180.0),
        zones=zones,
        plays=tuple(plays),
        preferred_limb=Limb(t.text("preferred_limb", choices=[limb.value for limb in Limb])),
        min_time_gap_s=t.number("min_time_gap_s", lo=0.0, hi=2.0),
        elasticity=t.number("elasticity", lo=0.0, hi=1.0),
        pedal_position_m=pedal,
        double_pedal=double,
        swing_deg=swing,
    )
    _check_above_floor(t, piece)
    t.done()
    return piece


def _check_above_floor(t: Table, piece: Piece) -> None:
    """The playing surface's lowest rim point and the footboard must not be under the floor.

    The floor is z = 0 (see :mod:`livedrummer.kit.model`). Hands cannot strike through it and a
    foot cannot press a pedal sunk into it, yet the IK (:func:`livedrummer.body.rig.build_rig`)
    reaches below z = 0 (a foot finds a footboard 0.3 m under it), so it would not refuse
    such a kit by itself.
    """
    lowest = piece.position_m[2] - piece.radius_m * math.sin(math.radians(piece.tilt_deg))
    if lowest < -_FLOOR_TOLERANCE_M:
        raise t.fail(
            "position_m",
            f"the playing surface's rim reaches {-lowest:.3f} m below the floor (z = 0)",
            list(piece.position_m),
        )
    pedal = piece.pedal_position_m
    if pedal is not None and pedal[2] < -_FLOOR_TOLERANCE_M:
        raise t.fail("pedal_position_m", f"is {-pedal[2]:.3f} m below the floor", list(pedal))


def _choices(t: Table, key: str, allowed: list[str], default: list[str]) -> list[str]:
    values = list(t.texts(key, tuple(default)))
    for v in values:
        if v not in allowed:
            raise t.fail(key, f"{v!r} is not one of {', '.join(allowed)}", values)
    if len(set(values)) != len(values):
        raise t.fail(key, "lists a value twice", values)
    return values


def load_kit_file(path: Path) -> Kit:
    """Load one kit file."""
    return parse_kit(read_toml(path, KitError), str(path))


def load_kit(spec: str) -> Kit:
    """A kit by path or name; ``NAME-left`` / ``NAME-right`` mirror kit NAME; ``KIT+EXT`` adds
    the extension EXT's pieces (see the module docstring)."""
    if looks_like_path(spec):
        return load_kit_file(Path(spec))
    if "+" in spec:
        base, *extensions = spec.split("+")
        kit = load_kit(base)
        for name in extensions:
            kit = extend_kit(kit, name)
        return replace(kit, name=spec)
    found = entries("kits")
    if spec in found:
        return load_kit_file(found[spec].path)
    for suffix, hand in _MIRROR_SUFFIX.items():
        base = spec.removesuffix(suffix)
        if base != spec and base in found:
            kit = load_kit_file(found[base].path)
            if kit.handedness == hand:
                raise KitError(f"kit {base!r} is already {hand}-handed; use {base!r}")
            return kit.mirrored(spec)
    known = ", ".join(kit_names()) or "(none)"
    raise KitError(f"unknown kit {spec!r}; known kits: {known}")


def load_extension(name: str) -> tuple[str, tuple[Piece, ...]]:
    """An extension's handedness and pieces (``kits/extensions/NAME.toml``)."""
    found = entries("kits/extensions")
    if name not in found:
        known = ", ".join(sorted(found)) or "(none)"
        raise KitError(f"unknown kit extension {name!r}; known extensions: {known}")
    source = str(found[name].path)
    root = Table(read_toml(found[name].path, KitError), source, "", KitError)
    head = root.table("extension")
    if head.text("name") != name:
        raise head.fail("name", f"must equal the file name {name!r}", head.text("name"))
    head.text("description", "")
    hand = head.text("handedness", "right", choices=("right", "left"))
    head.done()
    tables = root.tables("piece", label="name")
    if not tables:
        raise root.fail("piece", "an extension needs at least one [[piece]]")
    pieces = tuple(_parse_piece(t) for t in tables)
    root.done()
    return hand, pieces


def extend_kit(kit: Kit, extension: str) -> Kit:
    """``kit`` with the pieces of ``extension`` (mirrored for a kit of the other hand)."""
    hand, pieces = load_extension(extension)
    if hand != kit.handedness:
        pieces = tuple(p.mirrored() for p in pieces)
    have = {p.name for p in kit.pieces}
    for p in pieces:
        if p.name in have:
            raise KitError(
                f"kit extension {extension!r}: kit {kit.name!r} already has a piece "
                f"named {p.name!r}"
            )
    return Kit(
        name=f"{kit.name}+{extension}",
        description=f"{kit.description}, with {extension}",
        handedness=kit.handedness,
        seat_height_m=kit.seat_height_m,
        pieces=kit.pieces + pieces,
        pairs=kit.pairs,
        source=f"{kit.source} + extension {extension}",
        lights=kit.lights,
    )


def kit_names() -> list[str]:
    """Every selectable kit name, mirrored variants included."""
    names = []
    for name, entry in sorted(entries("kits").items()):
        names.append(name)
        try:
            hand = load_kit_file(entry.path).handedness
        except KitError:
            continue  # listed by `livedrummer kits` with its error
        names.append(f"{name}-{'left' if hand == 'right' else 'right'}")
    return names


def kit_that_plays(kit: Kit, instruments: Collection[str]) -> str | None:
    """The name of ``kit`` with a bundled extension that gives it a piece for every one of
    ``instruments`` (``rock5+percussion`` for a tambourine and a cowbell), or None when none
    does or ``kit`` came from a file path (a name is what ``--kit`` is told)."""
    if not instruments or looks_like_path(kit.name):
        return None
    for extension in sorted(entries("kits/extensions")):
        try:
            extended = extend_kit(kit, extension)
        except KitError:
            continue  # it adds a piece the kit has, or is broken: `livedrummer kits` says so
        if all(extended.resolve(name) is not None for name in instruments):
            return extended.name
    return None
