"""One synth's pose stream as a display reads it: the receiver, the pose track, the counts.

Why shared. The live display (one drummer) and the stage display (one stream per drummer) read
the same stream the same way: a synth's POSE messages go into a
:class:`~livedrummer.live.track.PoseTrack` at their show times, and the onsets, controls and
stage cues the synth forwards on that stream (SHOWN_ONSET, SHOWN_CONTROL, STAGE_CUE) share its
numbers, so they are taken and numbered too, never counted as bad or as loss. Both used to
keep a near-copy of that loop with different restart rules; :class:`PoseStream` is it once,
on the one :class:`~services.wire.stream_rx.StreamReceiver`. What a display does with the forwarded
messages (sound, strips, cues) stays the display's: :meth:`PoseStream.drain` hands them back.

A restarted synth (its numbers begin again) is taken and counted in ``restarts``; its poses go
on into the same track, since show times are on the shared clock and need no reset.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import zmq

from livedrummer.body.pose import pose_dtype
from livedrummer.kit.model import Kit
from livedrummer.live.track import PoseTrack
from livedrummer.protocol import Kind, Message, Pose, PoseFormat

from ..wire.badmsg import BadMessages
from ..wire.net import Security
from ..wire.stream_rx import DRAIN_BUDGET, StreamReceiver

POSE_STREAM_KINDS = (Kind.POSE, Kind.SHOWN_ONSET, Kind.SHOWN_CONTROL, Kind.STAGE_CUE)


@dataclass
class StreamStats:
    pose_messages: int = 0
    pose_samples: int = 0
    missing: int = 0
    bad: int = 0
    restarts: int = 0  # its synth started again (its numbers began again)
    lit_frames: int = 0  # frames that drew one of its pieces lit (the stage display's)


@dataclass
class PoseBatch:
    """One drain: each POSE's show times and rows (already in the track), and the rest."""

    poses: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    forwarded: list[Message] = field(default_factory=list)  # SHOWN_*, STAGE_CUE, in order


class PoseStream:
    """See the module docstring. ``performer``: the one performer this stream is (None:
    whoever the synth says; a message of another is dropped as unexpected)."""

    def __init__(
        self, kit: Kit, where: str, log: logging.Logger, performer: int | None = None
    ) -> None:
        self.format = PoseFormat.from_dtype(pose_dtype(len(kit.pieces)))
        self.rx = StreamReceiver(where, log, POSE_STREAM_KINDS, self.format, performer)
        self.track = PoseTrack()
        self.stats = StreamStats()

    @property
    def bad(self) -> BadMessages:
        return self.rx.bad

    def connect(
        self,
        ctx: zmq.Context[zmq.Socket[bytes]],
        endpoint: str,
        what: str,
        security: Security | None = None,
    ) -> None:
        self.rx.connect(ctx, endpoint, what, security)

    def drain(self, budget: int = DRAIN_BUDGET) -> PoseBatch:
        batch = self.rx.drain(budget)
        out = PoseBatch()
        s = self.stats
        s.missing += batch.missing
        s.bad += batch.bad
        s.restarts += batch.restarts
        for msg in batch.messages:
            if isinstance(msg.body, Pose):
                rows = msg.body.rows
                show = msg.body.time_s + rows["time_s"].astype(np.float64)
                self.track.add(show, rows)
                s.pose_messages += 1
                s.pose_samples += rows.size
                out.poses.append((show, rows))
            else:
                out.forwarded.append(msg)
        return out

    def unexpected(self, what: str) -> None:
        """A forwarded message this display cannot serve: counted as bad."""
        self.stats.bad += 1
        self.rx.unexpected(what)

    def close(self) -> None:
        self.rx.close()
