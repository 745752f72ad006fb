"""The overlays' models: SMED's scrolling score and its joint-angle graph, as plain arrays.

SMED (thesis, section 4.1.1) had two animated side windows: a *score window* that scrolls the
drum score past a red bar marking the present, with "a four second lookahead and four second
history", and a *graph window*, a scrolling plot of the shoulder, elbow and wrist angles,
colour coded and superimposed. Here both are strips over the bottom of the frame, on one time
axis: ``x = 0`` is ``t - HISTORY_S``, ``x = 1`` is ``t + LOOKAHEAD_S`` and the now-line is at
``x = 0.5``, so a note and the arm motion that plays it line up vertically. This module only
decides *what* is visible at a time; :mod:`livedrummer.render.overlay_raster` paints it.

* :class:`ScoreModel`: every onset of the sticking (its possibly substituted onsets, so a hi-hat
  note played with the pedal sits on the hi-hat lane with the left foot's colour) with its lane,
  velocity and limb, sorted by time; :meth:`ScoreModel.view` cuts the window with two binary
  searches. Lanes follow a drum staff, top to bottom: cymbals, hi-hat, other percussion,
  snare, toms, kick; one lane per kit piece (kit order within a group) or, with
  ``grouped=True``, one lane per group. Onsets the kit has no piece for are not drawn; they are
  counted in :attr:`ScoreModel.unplaced` and logged once.
* :func:`joint_angles`: per arm, in degrees, from joint positions (flexion, 0 = straight, the
  convention of ``livedrummer check``): *shoulder* = angle between the spine's downward
  direction (chest to lower back) and the upper arm (0 = arm hanging along the spine, 90 = arm
  at right angles to it); *elbow* = angle between the upper arm (shoulder to elbow) and the
  forearm (elbow to wrist), 0 = straight arm, 90 = right angle; *wrist* = angle between the
  forearm and the stick (grip fulcrum to tip), 0 = stick in line with the forearm.
* :class:`AngleModel`: those six angles sampled once per performance at ``rate_hz`` (60 Hz), so
  a frame only slices an array; :meth:`AngleModel.view` gives the samples in the same window.

Limits: the score shows onsets, not note lengths or a musical staff; the angle model is
precomputed for a file's performance (a live feed would append samples instead).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from livedrummer.body.skeleton import ARM, J
from livedrummer.errors import LivedrummerError
from livedrummer.kit.model import Kit
from livedrummer.kit.vocabulary import PieceKind
from livedrummer.render.body_scene import BodyScene
from livedrummer.sticking.result import Sticking

log = logging.getLogger(__name__)

HISTORY_S = 4.0
LOOKAHEAD_S = 4.0
ANGLE_RATE_HZ = 60.0
#: The overlays by name, top to bottom as they are stacked.
OVERLAYS: tuple[str, ...] = ("score", "joints")
#: Columns of :func:`joint_angles`.
ANGLE_NAMES: tuple[str, ...] = (
    "r_shoulder",
    "r_elbow",
    "r_wrist",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
)

#: Staff groups, top to bottom.
GROUPS: tuple[str, ...] = ("cymbals", "hihat", "percussion", "snare", "toms", "kick")
_GROUP_OF: dict[PieceKind, str] = {
    PieceKind.CRASH: "cymbals", PieceKind.RIDE: "cymbals", PieceKind.SPLASH: "cymbals",
    PieceKind.CHINA: "cymbals", PieceKind.HIHAT: "hihat", PieceKind.COWBELL: "percussion",
    PieceKind.TAMBOURINE: "percussion", PieceKind.PERCUSSION: "percussion",
    PieceKind.SNARE: "snare", PieceKind.TOM: "toms", PieceKind.KICK: "kick",
}  # fmt: skip
_GROUP_LABEL = {
    "cymbals": "CY",
    "hihat": "HH",
    "percussion": "PC",
    "snare": "SN",
    "toms": "TM",
    "kick": "KK",
}
_KIND_LABEL: dict[PieceKind, str] = {
    PieceKind.KICK: "KK", PieceKind.SNARE: "SN", PieceKind.TOM: "T", PieceKind.HIHAT: "HH",
    PieceKind.CRASH: "CR", PieceKind.RIDE: "RD", PieceKind.SPLASH: "SP", PieceKind.CHINA: "CH",
    PieceKind.COWBELL: "CB", PieceKind.TAMBOURINE: "TB", PieceKind.PERCUSSION: "PC",
}  # fmt: skip


class OverlayError(LivedrummerError):
    """An ``--overlay`` value names no overlay."""


def parse_overlays(text: str) -> frozenset[str]:
    """``"score,joints"`` -> the set of overlay names; ``""`` or ``"none"`` -> no overlay."""
    names = [n.strip().lower() for n in text.split(",") if n.strip()]
    if names == ["none"]:
        return frozenset()
    bad = [n for n in names if n not in OVERLAYS]
    if bad:
        raise OverlayError(
            f"--overlay {text!r}: unknown overlay {bad[0]!r} (known: {', '.join(OVERLAYS)})"
        )
    return frozenset(names)


def window_x(time_s: np.ndarray, now_s: float) -> np.ndarray:
    """Position on the strip's time axis in [0, 1] (0.5 = now) of ``time_s``."""
    return 0.5 + (np.asarray(time_s, np.float64) - now_s) / (HISTORY_S + LOOKAHEAD_S)


@dataclass(frozen=True)
class Lanes:
    """The score's lanes: ``lane_of_piece[p]`` is the lane (0 = top) of ``kit.pieces[p]``."""

    lane_of_piece: np.ndarray  # int (P,)
    labels: tuple[str, ...]  # short upper-case name per lane

    @property
    def count(self) -> int:
        return len(self.labels)

    @classmethod
    def from_kit(cls, kit: Kit, grouped: bool = False) -> Lanes:
        groups = [_GROUP_OF[p.kind] for p in kit.pieces]
        if grouped:
            present = [g for g in GROUPS if g in groups]
            lane = np.array([present.index(g) for g in groups], np.int64)
            return cls(lane, tuple(_GROUP_LABEL[g] for g in present))
        order = sorted(range(len(kit.pieces)), key=lambda p: (GROUPS.index(groups[p]), p))
        lane = np.empty(len(kit.pieces), np.int64)
        lane[order] = np.arange(len(order))
        return cls(lane, tuple(_piece_label(kit, p) for p in order))


def _piece_label(kit: Kit, p: int) -> str:
    piece = kit.pieces[p]
    digits = piece.name[len(piece.name.rstrip("0123456789")) :]
    return (_KIND_LABEL[piece.kind] + digits)[:3]


@dataclass(frozen=True)
class ScoreView:
    """The notes inside the window at ``now_s``, oldest first."""

    now_s: float
    x: np.ndarray  # float64 (n,), 0..1, 0.5 = now
    lane: np.ndarray  # int (n,)
    velocity: np.ndarray  # uint8 (n,)
    limb: np.ndarray  # int8 (n,), index into LIMBS or NOT_PLAYED


@dataclass(frozen=True)
class ScoreModel:
    """A performance's notes by time, lane, velocity and limb (see the module docstring)."""

    time_s: np.ndarray  # float64 (n,), sorted
    lane: np.ndarray  # int (n,)
    velocity: np.ndarray  # uint8 (n,)
    limb: np.ndarray  # int8 (n,)
    lanes: Lanes
    unplaced: int = 0

    @classmethod
    def from_sticking(cls, sticking: Sticking, kit: Kit, grouped: bool = False) -> ScoreModel:
        lanes = Lanes.from_kit(kit, grouped)
        piece = np.asarray(sticking.piece, np.int64)
        placed = piece >= 0
        unplaced = int(np.count_nonzero(~placed))
        if unplaced:
            log.warning(
                "score overlay: %d onsets have no piece on kit %s and are not drawn",
                unplaced,
                kit.name,
            )
        onsets = sticking.onsets[placed]
        order = np.argsort(onsets["time_s"], kind="stable")
        return cls(
            time_s=np.asarray(onsets["time_s"], np.float64)[order],
            lane=lanes.lane_of_piece[piece[placed]][order],
            velocity=np.asarray(onsets["velocity"], np.uint8)[order],
            limb=np.asarray(sticking.limb, np.int8)[placed][order],
            lanes=lanes,
            unplaced=unplaced,
        )

    def view(self, now_s: float) -> ScoreView:
        """The notes with ``now_s - HISTORY_S <= time_s <= now_s + LOOKAHEAD_S``."""
        lo = int(np.searchsorted(self.time_s, now_s - HISTORY_S, side="left"))
        hi = int(np.searchsorted(self.time_s, now_s + LOOKAHEAD_S, side="right"))
        return ScoreView(
            now_s,
            window_x(self.time_s[lo:hi], now_s),
            self.lane[lo:hi],
            self.velocity[lo:hi],
            self.limb[lo:hi],
        )


def _flexion_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle in degrees between vectors ``a`` and ``b`` (..., 3); 0 where either is zero."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    out: np.ndarray = np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1)))
    return out


def joint_angles(joints: np.ndarray) -> np.ndarray:
    """(..., 6) float64 degrees in :data:`ANGLE_NAMES` order from body joints (..., 24, 3).

    Definitions in the module docstring (flexion: 0 = straight)."""
    p = np.asarray(joints, np.float64)
    down = p[..., J["lower_back"], :] - p[..., J["chest"], :]
    cols = []
    for side in ("R", "L"):
        sh, el, wr, st, tip = ARM[side]
        upper = p[..., el, :] - p[..., sh, :]
        fore = p[..., wr, :] - p[..., el, :]
        stick = p[..., tip, :] - p[..., st, :]
        cols += [_flexion_deg(down, upper), _flexion_deg(upper, fore), _flexion_deg(fore, stick)]
    return np.stack(cols, axis=-1)


@dataclass(frozen=True)
class AngleView:
    """The angle samples inside the window at ``now_s``, oldest first."""

    now_s: float
    x: np.ndarray  # float64 (m,), 0..1, 0.5 = now
    degrees: np.ndarray  # float32 (m, 6)


@dataclass(frozen=True)
class AngleModel:
    """Six joint angles sampled at ``rate_hz`` from ``t = 0`` (see the module docstring)."""

    rate_hz: float
    degrees: np.ndarray  # float32 (N, 6), sample i at i / rate_hz

    @classmethod
    def from_joints(cls, joints: np.ndarray, rate_hz: float = ANGLE_RATE_HZ) -> AngleModel:
        """From joint positions (N, 24, 3) sampled at ``i / rate_hz``."""
        return cls(rate_hz, joint_angles(joints).astype(np.float32))

    @classmethod
    def from_body(
        cls, body: BodyScene, duration_s: float, rate_hz: float = ANGLE_RATE_HZ, chunk: int = 2048
    ) -> AngleModel:
        """The body's angles over ``[0, duration_s]`` (sampled ``chunk`` times at a go)."""
        times = np.arange(int(np.floor(max(duration_s, 0.0) * rate_hz)) + 1) / rate_hz
        parts = [
            joint_angles(body.poses(times[i : i + chunk])["position"]).astype(np.float32)
            for i in range(0, times.size, chunk)
        ]
        return cls(rate_hz, np.concatenate(parts))

    @property
    def duration_s(self) -> float:
        return (len(self.degrees) - 1) / self.rate_hz

    def view(self, now_s: float) -> AngleView:
        """Samples with ``now_s - HISTORY_S <= time <= now_s + LOOKAHEAD_S``, plus the sample
        just outside each end, so a curve reaches the strip's edges."""
        n = len(self.degrees)
        lo = max(int(np.floor((now_s - HISTORY_S) * self.rate_hz)), 0)
        hi = min(int(np.ceil((now_s + LOOKAHEAD_S) * self.rate_hz)) + 1, n)
        idx = np.arange(lo, max(hi, lo))
        return AngleView(now_s, window_x(idx / self.rate_hz, now_s), self.degrees[lo:hi])


class OverlayModels:
    """A performance's score and angle models, each made on first use (the window may never
    show one); ``duration_s`` is how far the angles are sampled."""

    def __init__(self, body: BodyScene, duration_s: float) -> None:
        self.body, self.duration_s = body, duration_s
        self._score: dict[bool, ScoreModel] = {}
        self._angles: AngleModel | None = None

    def score(self, grouped: bool = False) -> ScoreModel:
        """The score with a lane per piece, or per group (``grouped``)."""
        if grouped not in self._score:
            self._score[grouped] = ScoreModel.from_sticking(
                self.body.performed.sticking, self.body.kit, grouped
            )
        return self._score[grouped]

    @property
    def angles(self) -> AngleModel:
        if self._angles is None:
            self._angles = AngleModel.from_body(self.body, self.duration_s)
        return self._angles
