"""The stage file: who plays, what, on which kit, where they stand (TOML, read strictly).

Example::

    [formation]
    shape = "arc"          # line, arc, grid, v, explicit (livedrummer.stage.formation)
    spacing = 2.6          # metres between neighbours
    facing = "audience"    # audience, center, or degrees
    # radius = 6.0, span_deg = 120, columns = 4, positions = [[0, 0], [3, -1]], symmetric

    [[performer]]
    id = "lead"
    file = "song.mid"      # relative to this file; or source = "remote:tcp://HOST:5710"
    channel = 10           # this performer's channel in a shared file (default: auto)
    kit = "rock5"          # and map, avatar, preset, as on the command line
    position = [0, 1.5]    # overrides the formation for this performer
    yaw = 0

    [ensemble]             # optional: `copies` drummers play each performer's part,
    copies = 4             # made to differ by livedrummer.stage.variation
    warp_ms = 30
    amplitude = 0.2
    mode = "bar"
    seed = 1

Every key is checked (:class:`~livedrummer.config.Table`): an unknown key, a wrong type or an
out-of-range value is one line naming the file, the table and the key. Performer ids must be
unique; ``file`` paths are resolved against the stage file's folder. A performer's live
``source`` (``midi:PORT``, ``virtual:NAME``, ``remote:EP,control=EP``, ...) is checked here by
:func:`livedrummer.stage.source.parse_source` and kept as text; ``up --stage`` opens it.

Limits: one formation for the whole piece; performers of a shared file are told apart by
channel, not by track.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError
from livedrummer.kit.lights import LightSpec, parse_light_spec

from .formation import FACINGS, SHAPES, Formation, Placement, place
from .source import parse_source
from .variation import MODES, Variation


class StageError(ConfigError):
    """A stage file is wrong."""


@dataclass(frozen=True)
class Performer:
    id: str
    file: Path | None = None
    source: str | None = None
    channel: str = "auto"
    kit: str = "rock5"
    map: str = "auto"
    avatar: str | None = None
    preset: str | None = None
    position: tuple[float, float] | None = None
    yaw_deg: float | None = None
    copy: int = 0  # which copy of an ensemble (0: the performer itself)


@dataclass(frozen=True)
class Stage:
    performers: tuple[Performer, ...]
    formation: Formation = field(default_factory=Formation)
    ensemble: Variation | None = None
    copies: int = 1
    source: str = ""
    placements: tuple[Placement, ...] = field(default=())
    lights: LightSpec | None = None  # the [lights] table (livedrummer.kit.lights)

    def players(self) -> list[tuple[Performer, Placement, Variation | None]]:
        """Every drummer on the stage: each performer ``copies`` times, with its spot and the
        variation its copy plays with (None for the performer itself)."""
        out = []
        k = 0
        for performer in self.performers:
            for c in range(self.copies):
                var = None
                if c > 0 and self.ensemble is not None:
                    var = replace(self.ensemble, seed=self.ensemble.seed * 1000 + k)
                out.append(
                    (Performer(**{**performer.__dict__, "copy": c}), self.placements[k], var)
                )
                k += 1
        return out

    def live(self) -> list[tuple[int, Performer, Placement]]:
        """The drummers played live (a performer with a ``source``, and each of its ensemble
        copies), each with its performer id (its index in :meth:`players`, the id its synth
        and pose stream carry; a performer's own index in the file when there are no copies)
        and its spot. A copy (``copy > 0``) plays its performer's input through a synth of its
        own with :meth:`variation` (``synth --vary``). Raises StageError when none has a
        source."""
        out = [
            (k, p, spot) for k, (p, spot, _var) in enumerate(self.players()) if p.source is not None
        ]
        if not out:
            raise StageError(f'{self.source}: no performer has a live source = "..."')
        return out

    def variation(self, k: int) -> Variation | None:
        """The variation drummer ``k`` of :meth:`players` plays with (None: the performer)."""
        return self.players()[k][2]


def load_stage(path: Path) -> Stage:
    """Read and check a stage file (see the module docstring)."""
    data = read_toml(path, StageError)
    top = Table(data, str(path), "", StageError)
    formation = _formation(top.table("formation") if top.has("formation") else None)
    performers: list[Performer] = []
    for t in top.tables("performer", "id"):
        performers.append(_performer(t, path.parent))
    if not performers:
        raise StageError(f"{path}: no [[performer]] tables: a stage needs at least one")
    ids = [p.id for p in performers]
    for pid in ids:
        if ids.count(pid) > 1:
            raise StageError(f"{path}: performer id {pid!r} is used twice")
    ensemble, copies = None, 1
    if top.has("ensemble"):
        e = top.table("ensemble")
        copies = int(e.integer("copies", 2, 1, 64))
        ensemble = Variation(
            warp_s=e.number("warp_ms", 30.0, 0.0, 250.0) / 1000.0,
            freq_max=e.number("freq_max", 2.0, 0.5, 8.0),
            amplitude=e.number("amplitude", 0.2, 0.0, 0.9),
            mode=e.text("mode", "bar", MODES),
            seed=int(e.integer("seed", 1, 0, 2**31)),
        )
        e.done()
    lights = parse_light_spec(top.table("lights")) if top.has("lights") else None
    top.done()
    count = len(performers) * copies
    try:
        spots = place(formation, count)
    except ValueError as exc:
        raise StageError(f"{path}: [formation] {exc}") from None
    who = [(p, c) for p in performers for c in range(copies)]
    spots = [_own_spot(p, s) if c == 0 else s for (p, c), s in zip(who, spots, strict=True)]
    return Stage(tuple(performers), formation, ensemble, copies, str(path), tuple(spots), lights)


def _own_spot(p: Performer, s: Placement) -> Placement:
    """A performer's own ``position``/``yaw``, where given, over the formation's spot."""
    x, y = p.position if p.position is not None else (s.x, s.y)
    return Placement(x, y, p.yaw_deg if p.yaw_deg is not None else s.yaw_deg)


def _formation(t: Table | None) -> Formation:
    if t is None:
        return Formation()
    shape = t.text("shape", "line", SHAPES)
    if isinstance(t.raw("facing", "audience"), str):  # a name or a number of degrees
        facing: str | float = t.text("facing", "audience", FACINGS)
    else:
        facing = t.number("facing", 0.0, -360.0, 360.0)
    positions: tuple[tuple[float, float], ...] = ()
    if t.has("positions"):
        raw = t.raw("positions")
        if not isinstance(raw, list) or not all(
            isinstance(p, list)
            and len(p) == 2
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in p)
            for p in raw
        ):
            raise t.fail("positions", "expected a list of [x, y] pairs in metres", raw)
        positions = tuple((float(x), float(y)) for x, y in raw)
    try:
        f = Formation(
            shape=shape,
            spacing=t.number("spacing", 2.6, 0.5, 50.0),
            radius=t.number("radius", 6.0, 0.5, 100.0),
            span_deg=t.number("span_deg", 120.0, 0.0, 360.0),
            columns=int(t.integer("columns", 4, 1, 64)),
            facing=facing,
            symmetric=t.boolean("symmetric", False),
            positions=positions,
        )
    except ValueError as exc:
        raise t.fail(None, str(exc)) from None
    t.done()
    return f


def _performer(t: Table, folder: Path) -> Performer:
    pid = t.text("id")
    file = t.text("file", None)
    source = t.text("source", None)
    if file is None and source is None:
        raise t.fail(None, 'needs file = "part.mid" (render) or source = "..." (live)')
    if source is not None:
        try:
            parse_source(source, folder)
        except ValueError as exc:
            raise t.fail("source", str(exc), source) from None
    position = tuple(t.vector("position", 2)) if t.has("position") else None
    channel = t.raw("channel", "auto")
    number = isinstance(channel, int) and not isinstance(channel, bool)
    if not (channel in ("auto", "all") or (number and 1 <= channel <= 16)):
        raise t.fail("channel", 'expected 1..16, "all" or "auto"', channel)
    p = Performer(
        id=pid,
        file=None if file is None else (folder / file),
        source=source,
        channel=str(channel),
        kit=t.text("kit", "rock5"),
        map=t.text("map", "auto"),
        avatar=t.text("avatar", None),
        preset=t.text("preset", None),
        position=None if position is None else (float(position[0]), float(position[1])),
        yaw_deg=t.number("yaw", None, -360.0, 360.0) if t.has("yaw") else None,
    )
    t.done()
    return p
