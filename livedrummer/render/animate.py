"""Kit motion from onsets: hit highlight, cymbal and drum wobble, hi-hat opening, kick beater.

Given a performance's onsets, a kit and the frame times, :func:`kit_channels` returns the
``(F, P, 4)`` kit channels of :mod:`livedrummer.scene` for every frame at once: per piece, each
frame looks up the last and next stroke on that piece (``searchsorted``) and evaluates closed
forms of the time since it. The highlight peaks in the frame of contact and fades in a quarter
second; a struck cymbal tilts away from the drummer and swings back as a damped oscillation;
drums nod a little; the hi-hat top cymbal sits at the opening of the last hi-hat stroke; the
kick beater rests back from the head, swings in just before a kick and returns after it.

This is the kit's reaction only; the body model moves the drummer. Limits: pedal controller
(CC4) motion between strokes and cymbal chokes are not shown; each piece wobbles about one axis.
"""

from __future__ import annotations

import numpy as np

from livedrummer.kit import Kit
from livedrummer.scene import CH_HIGHLIGHT, CH_TRAVEL, CH_WOBBLE, CH_WOBBLE_AZIMUTH, N_CHANNELS
from livedrummer.vocabulary import INSTRUMENTS, PieceKind

HIGHLIGHT_DECAY_S = 0.09
CYMBAL_TILT_RAD = 0.16
CYMBAL_DECAY_S = 0.7
CYMBAL_SWING_HZ = 2.2
DRUM_NOD_RAD = 0.025
DRUM_DECAY_S = 0.08
HIHAT_LIFT_M = 0.028
BEATER_REST_RAD = 0.6
BEATER_RETURN_S = 0.12
BEATER_APPROACH_S = 0.07


def onset_pieces(onsets: np.ndarray, kit: Kit) -> np.ndarray:
    """Index into ``kit.pieces`` of the piece each onset sounds on (-1: the kit has none)."""
    table = np.full(len(INSTRUMENTS), -1, np.int32)
    for code, name in enumerate(INSTRUMENTS):
        piece = kit.resolve(name)
        if piece is not None:
            table[code] = kit.pieces.index(piece)
    return table[onsets["instrument"].astype(np.intp)]


def kit_channels(onsets: np.ndarray, kit: Kit, times_s: np.ndarray) -> np.ndarray:
    """Kit channels (F, P, 4) float32 at ``times_s`` (F,), see the module docstring."""
    times = np.asarray(times_s, np.float64)
    out = np.zeros((times.size, len(kit.pieces), N_CHANNELS), np.float32)
    pieces = onset_pieces(onsets, kit)
    for p, piece in enumerate(kit.pieces):
        mask = pieces == p
        t_hit = onsets["time_s"][mask]
        vel = onsets["velocity"][mask].astype(np.float64) / 127.0
        toward_seat = np.arctan2(-piece.position_m[1], -piece.position_m[0])
        out[:, p, CH_WOBBLE_AZIMUTH] = toward_seat + np.pi / 2
        if piece.kind is PieceKind.KICK:
            out[:, p, CH_TRAVEL] = BEATER_REST_RAD
        if t_hit.size == 0:
            continue
        last = np.searchsorted(t_hit, times, side="right") - 1
        played = last >= 0
        li = np.maximum(last, 0)
        since = np.where(played, times - t_hit[li], np.inf)
        v = np.where(played, vel[li], 0.0)
        out[:, p, CH_HIGHLIGHT] = v * np.exp(-since / HIGHLIGHT_DECAY_S)
        if piece.kind.is_cymbal and piece.kind is not PieceKind.HIHAT:
            swing = np.cos(2 * np.pi * CYMBAL_SWING_HZ * np.where(played, since, 0.0))
            out[:, p, CH_WOBBLE] = CYMBAL_TILT_RAD * v * np.exp(-since / CYMBAL_DECAY_S) * swing
        elif not piece.kind.is_cymbal:
            out[:, p, CH_WOBBLE] = DRUM_NOD_RAD * v * np.exp(-since / DRUM_DECAY_S)
        if piece.kind is PieceKind.HIHAT:
            openness = np.nan_to_num(onsets["openness"][mask].astype(np.float64), nan=0.0)
            out[:, p, CH_TRAVEL] = np.where(played, openness[li], 0.0) * HIHAT_LIFT_M
        elif piece.kind is PieceKind.KICK:
            nxt = np.searchsorted(t_hit, times, side="left")
            until = np.where(nxt < t_hit.size, t_hit[np.minimum(nxt, t_hit.size - 1)] - times,
                             np.inf)  # fmt: skip
            back = np.minimum(since / BEATER_RETURN_S, until / BEATER_APPROACH_S)
            out[:, p, CH_TRAVEL] = BEATER_REST_RAD * np.clip(back, 0.0, 1.0)
    return out
