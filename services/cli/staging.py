"""Reading a stage's parts for the file commands (``check --stage``): one performance per drummer.

Each performer's part is its ``file`` read as ``read_performance`` reads any file (its
``map`` and ``channel``, its one-line report on stderr, once for a performer's copies);
an ensemble copy plays its performer's part varied by
:func:`livedrummer.stage.variation.vary_rows` over the file's own bars. The kit, avatar and
preset are the performer's. Not a subcommand: the commands that take ``--stage`` use it.
"""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from livedrummer.errors import LivedrummerError

from .files import read_performance

if TYPE_CHECKING:
    from livedrummer.midi.notemap import NoteMap
    from livedrummer.stage.formation import Placement
    from livedrummer.stage.stagefile import Performer, Stage
    from livedrummer.timeline.performance import Performance


@dataclass(frozen=True)
class Part:
    """One drummer of the stage: who, where, and the performance it plays."""

    performer: Performer
    placement: Placement
    performance: Performance
    note_map: NoteMap

    @property
    def label(self) -> str:
        p = self.performer
        return p.id if p.copy == 0 else f"{p.id}#{p.copy + 1}"


def check_room(stage: Stage) -> None:
    """A one-line StageError when two drummers of ``stage`` (copies too) stand closer than
    their kits' footprints allow (:func:`livedrummer.stage.layout.check_footprints`)."""
    from livedrummer.kit.loader import load_kit
    from livedrummer.stage.layout import check_footprints, footprint
    from livedrummer.stage.stagefile import StageError

    prints = {p.kit: footprint(load_kit(p.kit)) for p in stage.performers}
    players = stage.players()
    labels = [p.id if p.copy == 0 else f"{p.id}#{p.copy + 1}" for p, _s, _v in players]
    try:
        check_footprints(
            [s for _p, s, _v in players], [prints[p.kit] for p, _s, _v in players], labels
        )
    except ValueError as exc:
        shape = stage.formation.shape
        raise StageError(f"{stage.source}: [formation] {shape}: {exc}") from None


def stage_parts(stage: Stage, args: argparse.Namespace) -> list[Part]:
    """Every drummer's part (see the module docstring); a performer without a file is a one-
    line error (its ``source`` is for ``up --stage``), so are drummers whose kits would
    overlap (:func:`check_room`)."""
    from livedrummer.stage.variation import bar_edges, vary_rows

    check_room(stage)
    parts: list[Part] = []
    read: dict[str, tuple[Performance, NoteMap]] = {}
    for performer, placement, variation in stage.players():
        if performer.file is None:
            raise LivedrummerError(
                f"{stage.source}: performer {performer.id!r} has no file "
                f"(its source {performer.source!r} is played live)"
            )
        if performer.id not in read:
            opts = argparse.Namespace(map=performer.map, channel=performer.channel)
            read[performer.id] = read_performance(opts, Path(performer.file))
        performance, note_map = read[performer.id]
        if variation is not None:
            grid = performance.grid
            edges = bar_edges(grid.beat_s[grid.beat_in_bar == 0], performance.duration_s)
            onsets, controls = vary_rows(performance.onsets, performance.controls, edges, variation)
            performance = dataclasses.replace(performance, onsets=onsets, controls=controls)
        parts.append(Part(performer, placement, performance, note_map))
    return parts
