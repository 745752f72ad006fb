"""Sampling a whole performance into pose records: body, kit channels, chokes.

The one place that ties an :class:`~livedrummer.body.animation.Animation` to the kit
channels and the pose layout, so the CLI, the checker, the exporters and (later) the
streaming service all sample the same way. Work is done in chunks of times so memory stays
bounded on hour-long sets.
"""

from __future__ import annotations

import numpy as np

from livedrummer.body.animation import Animation
from livedrummer.body.channels import KitChannels, VibrationParams, kit_channels
from livedrummer.body.pose import pack_poses
from livedrummer.kit.behaviour import BEHAVIOURS, PedalMotion
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import Limb, PieceKind, Zone
from livedrummer.midi.notemap import NoteMap
from livedrummer.sticking.result import Sticking
from livedrummer.timeline.events import ControlKind

CHUNK = 50_000


def choke_times(controls: np.ndarray, note_map: NoteMap, anim: Animation) -> list[np.ndarray]:
    """Per piece, sorted times of grabs (aftertouch > 0) on the notes that sound it."""
    return kit_choke_times(controls, note_map, anim.rig.kit)


def kit_choke_times(controls: np.ndarray, note_map: NoteMap, kit: Kit) -> list[np.ndarray]:
    """:func:`choke_times` for a kit (the live synth's window has no animation yet)."""
    index = {p.name: i for i, p in enumerate(kit.pieces)}
    out: list[list[float]] = [[] for _ in kit.pieces]
    if controls.size:
        grabs = controls[(controls["kind"] == ControlKind.CHOKE) & (controls["value"] > 0)]
        for t, note in zip(grabs["time_s"].tolist(), grabs["number"].tolist(), strict=True):
            spec = note_map.lookup(int(note))
            piece = kit.resolve(spec.instrument) if spec is not None else None
            if piece is not None:
                out[index[piece.name]].append(t)
    return [np.asarray(v, dtype=np.float64) for v in out]


def channels_at(
    anim: Animation,
    sticking: Sticking,
    times: np.ndarray,
    chokes: list[np.ndarray] | None = None,
    vib: VibrationParams | None = None,
) -> KitChannels:
    kit = anim.rig.kit
    on = sticking.onsets
    played = (sticking.limb >= 0) & (sticking.piece >= 0)
    hits_s, hits_v, feet = [], [], []
    for k, piece in enumerate(kit.pieces):
        m = played & (sticking.piece == k)
        if piece.kind is PieceKind.HIHAT:
            m &= on["zone"] != list(Zone).index(Zone.PEDAL)
        hits_s.append(on["time_s"][m].astype(np.float64))
        hits_v.append(on["velocity"][m].astype(np.float64) / 127.0)
        foot = None
        pedal = BEHAVIOURS[piece.kind].pedal
        if pedal is not PedalMotion.NONE:
            limb = piece.limb_for(Zone.PEDAL if pedal is PedalMotion.HIHAT else Zone.HEAD)
            side = "r" if limb in (Limb.RF, Limb.RH) else "l"
            foot = anim.foot_lift(side, times)
        feet.append(foot)
    no_chokes = [np.zeros(0) for _ in kit.pieces]
    return kit_channels(
        kit.pieces, times, hits_s, hits_v, chokes or no_chokes, feet, anim.openness(times), vib
    )


def sample_poses(
    anim: Animation,
    sticking: Sticking,
    times: np.ndarray,
    chokes: list[np.ndarray] | None = None,
) -> np.ndarray:
    """Pose records (see :mod:`livedrummer.body.pose`) at ``times``."""
    parts = []
    for start in range(0, max(times.size, 1), CHUNK):
        t = np.asarray(times[start : start + CHUNK], dtype=np.float64)
        local, _, _, world_p = anim.solve(t)
        ch = channels_at(anim, sticking, t, chokes)
        parts.append(pack_poses(t, local, world_p, ch.swing, ch.lift, ch.glow))
    return np.concatenate(parts)
