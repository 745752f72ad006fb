"""How an offline render's frames are dealt to worker processes (``render --jobs N``).

Why this shape. A video has one encoder, and the encoder takes the frames in order: so the
frames cannot be cut into J long ranges, one per worker, without holding all but the first
range in memory until its turn (or encoding J videos whose decoded frames would differ from a
one-process render's at the cuts). Instead the frames are cut into short *chunks* of
consecutive frames, dealt round-robin: chunk ``c`` (frames ``c*chunk`` to ``(c+1)*chunk - 1``)
goes to worker ``c % jobs``. Each worker draws its chunks in time order, the parent takes
them in frame order, and while it takes one worker's chunk the others draw theirs, so each
worker needs at most about a chunk of frames waiting for the parent.

Cores: llvmpipe rasterises on ``LP_NUM_THREADS`` threads (default: every core), but much of
a frame (vertex shading, set-up, the read-back, Python) runs on one; J processes of
``cores // J`` threads each keep every core busy. :func:`threads_per_worker` chooses that.

Limits: the split is by frame count, not by cost, so a worker whose chunks are heavier (a
busier camera) finishes later; chunks keep that imbalance to one chunk's worth.
"""

from __future__ import annotations

import os

import numpy as np

from livedrummer.errors import ConfigError

#: frames per chunk: long enough that a chunk's start-up (the worker's catching up on the
#: frames it skipped, see services/display/parallel.py) is small, short enough that a
#: worker's waiting frames stay a few tens of megabytes at 720p
DEFAULT_CHUNK = 16
MAX_JOBS = 64
#: chunks a worker gets at least on ``--jobs auto`` (see :func:`default_jobs`)
MIN_CHUNKS = 2


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the OS tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # no affinity on this OS
        return max(1, os.cpu_count() or 1)


def default_jobs(cores: int, frames: int, chunk: int = DEFAULT_CHUNK) -> int:
    """Worker processes for ``frames`` frames on ``cores`` cores: one a core, each with at
    least :data:`MIN_CHUNKS` chunks, since a worker's start-up (a renderer of its own) costs
    about a chunk's drawing (one worker: the render stays in the calling process)."""
    return max(1, min(cores, MAX_JOBS, chunk_count(frames, chunk) // MIN_CHUNKS))


def threads_per_worker(cores: int, jobs: int) -> int:
    """llvmpipe threads for each of ``jobs`` workers so that workers x threads ~ cores."""
    return max(1, cores // max(1, jobs))


def chunk_count(frames: int, chunk: int = DEFAULT_CHUNK) -> int:
    return -(-max(0, frames) // chunk)


def owner_of(frame: int, jobs: int, chunk: int = DEFAULT_CHUNK) -> int:
    """The worker that draws frame ``frame``."""
    return (frame // chunk) % jobs


def worker_frames(frames: int, jobs: int, worker: int, chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    """The frame indices worker ``worker`` of ``jobs`` draws, ascending (int64)."""
    index = np.arange(max(0, frames), dtype=np.int64)
    picked: np.ndarray = index[(index // chunk) % jobs == worker]
    return picked


def parse_jobs(text: str | int | None) -> int | None:
    """``--jobs``: a worker count 1..64, or ``auto``/None for :func:`default_jobs`."""
    if text is None or str(text).strip().lower() == "auto":
        return None
    value = str(text).strip()
    if not value.isdigit() or not 1 <= int(value) <= MAX_JOBS:
        raise ConfigError(f"--jobs {text}: expected auto or a worker count 1..{MAX_JOBS}")
    return int(value)
