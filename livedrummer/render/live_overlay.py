"""SMED's score and joint-angle strips fed live: the onsets and poses a display receives.

The file overlays (:mod:`livedrummer.render.overlay`) slice a whole performance; a live display
only has what the synth has sent so far, stamped with show times on the shared clock. These
models keep that feed in growing arrays and answer the same ``view(now_s)`` calls, so the
rasteriser (:mod:`livedrummer.render.overlay_raster`) paints them unchanged.

* :class:`LiveScore`: the forwarded onsets (``SHOWN_ONSET`` rows, ``ONSET_DTYPE`` with the show
  time in ``time_s``), each put on its kit piece's lane with the file score's routing
  (:func:`livedrummer.sticking.prepare.route`: pieces, and the foot that plays a kick or a
  pedalled hi-hat). The hands' sticking is decided inside the synth and not forwarded; the
  poses tell it: once a pose message covers a hand note's show time, the stick tip nearer the
  note's piece then (:meth:`LiveScore.resolve_hands`) gives it its hand's colour; until then
  (or where no pose covers it) it is grey. Onsets the kit has no piece for are counted in
  :attr:`LiveScore.unplaced`.
* :class:`LiveAngles`: the six angles of :func:`~livedrummer.render.overlay.joint_angles` of
  every pose sample received, by show time. A newer message replaces the samples it overlaps
  (the synth re-animates and resends recent samples). :meth:`LiveAngles.view` resamples them
  linearly onto a ``rate_hz`` grid of absolute show time, the file graph's grid, so given the
  file's samples it gives the file's view.

Both forget what is older than ``keep_s`` (default: the strips' history plus a second), so a
show of hours costs the memory of seconds. Limits: the score shows onsets as received (a late
onset appears late); angles are not extrapolated past the newest sample (the graph ends there).
"""

from __future__ import annotations

import numpy as np

from livedrummer.body.skeleton import J
from livedrummer.kit.model import Kit
from livedrummer.render.font5x7 import GLYPH_H
from livedrummer.render.overlay import (
    ANGLE_RATE_HZ,
    HISTORY_S,
    LOOKAHEAD_S,
    AngleView,
    Lanes,
    ScoreView,
    joint_angles,
    window_x,
)
from livedrummer.render.overlay_raster import OverlayImage, font_scale, strip_heights
from livedrummer.sticking.prepare import route
from livedrummer.sticking.result import NOT_PLAYED

KEEP_S = HISTORY_S + 1.0


class LiveScore:
    """The forwarded onsets by lane (see the module docstring)."""

    def __init__(self, kit: Kit, grouped: bool = False, keep_s: float = KEEP_S) -> None:
        self.kit, self.keep_s = kit, keep_s
        self.lanes = Lanes.from_kit(kit, grouped)
        self.time_s = np.zeros(0, np.float64)
        self.lane = np.zeros(0, np.int64)
        self.velocity = np.zeros(0, np.uint8)
        self.limb = np.zeros(0, np.int8)
        self.piece = np.zeros(0, np.int64)
        self.unplaced = 0
        self._centre = np.array([p.position_m for p in kit.pieces], np.float64).reshape(-1, 3)

    def add(self, onsets: np.ndarray) -> None:
        """Take forwarded onset rows (``ONSET_DTYPE``, ``time_s`` = show time)."""
        if onsets.size == 0:
            return
        routed = route(onsets, self.kit)
        placed = routed.piece >= 0
        self.unplaced += int(np.count_nonzero(~placed))
        t = np.concatenate([self.time_s, np.asarray(onsets["time_s"], np.float64)[placed]])
        lane = self.lanes.lane_of_piece[np.asarray(routed.piece, np.int64)[placed]]
        lane = np.concatenate([self.lane, lane])
        vel = np.concatenate([self.velocity, np.asarray(onsets["velocity"], np.uint8)[placed]])
        limb = np.concatenate([self.limb, np.asarray(routed.limb, np.int8)[placed]])
        piece = np.concatenate([self.piece, np.asarray(routed.piece, np.int64)[placed]])
        order = np.argsort(t, kind="stable")
        keep = order[t[order] >= t.max() - self.keep_s - LOOKAHEAD_S]
        self.time_s, self.lane = t[keep], lane[keep]
        self.velocity, self.limb, self.piece = vel[keep], limb[keep], piece[keep]

    def resolve_hands(self, time_s: np.ndarray, r_tip: np.ndarray, l_tip: np.ndarray) -> None:
        """Give each grey note inside ``time_s`` (sorted show times of poses, with the right
        and left stick tips (n, 3)) the hand whose tip is nearer its piece's centre then."""
        if time_s.size < 2:
            return
        todo = np.flatnonzero(
            (self.limb == NOT_PLAYED) & (self.time_s >= time_s[0]) & (self.time_s <= time_s[-1])
        )
        if todo.size == 0:
            return
        t = self.time_s[todo]
        centre = self._centre[self.piece[todo]]
        dist = []
        for tips in (r_tip, l_tip):
            at = np.stack([np.interp(t, time_s, tips[:, c]) for c in range(3)], axis=-1)
            dist.append(np.linalg.norm(at - centre, axis=-1))
        self.limb[todo] = np.where(dist[0] <= dist[1], 0, 1).astype(np.int8)

    def view(self, now_s: float) -> ScoreView:
        """The onsets with ``now_s - HISTORY_S <= time_s <= now_s + LOOKAHEAD_S``."""
        lo = int(np.searchsorted(self.time_s, now_s - HISTORY_S, side="left"))
        hi = int(np.searchsorted(self.time_s, now_s + LOOKAHEAD_S, side="right"))
        return ScoreView(
            now_s,
            window_x(self.time_s[lo:hi], now_s),
            self.lane[lo:hi],
            self.velocity[lo:hi],
            self.limb[lo:hi],
        )


class LiveAngles:
    """The received poses' joint angles, resampled on a grid (see the module docstring)."""

    def __init__(self, rate_hz: float = ANGLE_RATE_HZ, keep_s: float = KEEP_S) -> None:
        self.rate_hz, self.keep_s = rate_hz, keep_s
        self.time_s = np.zeros(0, np.float64)
        self.degrees = np.zeros((0, 6), np.float32)

    def add(self, show_s: np.ndarray, joints: np.ndarray) -> None:
        """Take pose samples: show times (n,) and joint positions (n, 24, 3)."""
        t = np.asarray(show_s, np.float64)
        if t.size == 0:
            return
        order = np.argsort(t, kind="stable")
        t = t[order]
        deg = joint_angles(np.asarray(joints)[order]).astype(np.float32)
        old = self.time_s < t[0]  # the new message replaces what it overlaps
        self.time_s = np.concatenate([self.time_s[old], t])
        self.degrees = np.concatenate([self.degrees[old], deg])
        keep = self.time_s >= self.time_s[-1] - self.keep_s - LOOKAHEAD_S
        self.time_s, self.degrees = self.time_s[keep], self.degrees[keep]

    def view(self, now_s: float) -> AngleView:
        """Grid samples from ``now_s - HISTORY_S`` to ``now_s + LOOKAHEAD_S`` (plus one beyond
        each end) where poses were received, interpolated linearly between them."""
        if self.time_s.size < 2:
            return AngleView(now_s, np.zeros(0), np.zeros((0, 6), np.float32))
        r = self.rate_hz
        lo = max(np.floor((now_s - HISTORY_S) * r), np.ceil(self.time_s[0] * r - 1e-6))
        hi = min(np.ceil((now_s + LOOKAHEAD_S) * r), np.floor(self.time_s[-1] * r + 1e-6))
        k = np.arange(int(lo), int(hi) + 1)
        times = k / r
        deg = np.stack(
            [np.interp(times, self.time_s, self.degrees[:, c]) for c in range(6)], axis=-1
        ).astype(np.float32)
        return AngleView(now_s, window_x(times, now_s), deg)


class LiveStrips:
    """Both live models, fed together, and the strips' image for a frame size and a set of
    strips (made again only when either changes: a window resized, a key pressed). The score
    has a lane per piece where those lanes fit their labels, else one per staff group, as in
    :func:`~livedrummer.render.overlay_raster.overlay_image`."""

    def __init__(self, kit: Kit) -> None:
        self.scores = {grouped: LiveScore(kit, grouped) for grouped in (False, True)}
        self.angles = LiveAngles()
        self._image: OverlayImage | None = None
        self._tips = (np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))  # the last message's

    def add_onsets(self, onsets: np.ndarray) -> None:
        for score in self.scores.values():
            score.add(onsets)
            score.resolve_hands(*self._tips)

    def add_poses(self, show_s: np.ndarray, joints: np.ndarray) -> None:
        self.angles.add(show_s, joints)
        t = np.asarray(show_s, np.float64)
        order = np.argsort(t, kind="stable")
        p = np.asarray(joints, np.float64)[order]
        self._tips = (t[order], p[:, J["r_tip"]], p[:, J["l_tip"]])
        for score in self.scores.values():
            score.resolve_hands(*self._tips)

    def image(self, frame_size: tuple[int, int], names: frozenset[str]) -> OverlayImage:
        img = self._image
        if img is None or tuple(img.frame_size) != tuple(frame_size) or img.names != names:
            score = self.scores[False]
            if "score" in names:
                height = strip_heights(frame_size[1], names)["score"]
                s = font_scale(height)
                if (height - (GLYPH_H + 4) * s - 2) / max(score.lanes.count, 1) < (GLYPH_H + 1) * s:
                    score = self.scores[True]
            img = OverlayImage((int(frame_size[0]), int(frame_size[1])), names, score, self.angles)
            self._image = img
        return img
