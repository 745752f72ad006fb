"""Frames drawn by worker processes and handed back in order (``render --jobs N``).

Why this shape. On a CPU (llvmpipe) a frame's rasterisation runs on several threads but much
of it (vertex shading, set-up, the read-back, the Python around it) on one, so one process
leaves cores idle; several processes, each with its own EGL context and ``LP_NUM_THREADS``
set so that workers x threads ~ cores, fill them. The deal of frames to workers is
:mod:`livedrummer.render.frame_split`'s (short chunks, round-robin).

The workers come from a fork server (:func:`start_server`: a fresh interpreter that imports
the renderer's modules once, then forks a worker per request), not from a fork of the caller:
a process that has made an OpenGL context before (a test, a show that renders a clip) holds
Mesa's threads and locks, and a fork of it can hang in its first EGL call. The server is
started early (``render`` does it before reading the file), so its start-up overlaps the
parent's; each worker gets the drawing job pickled once (:func:`payload`: the kit, the
performed body, the avatar, the cues; some 400 kB for the demo) and builds its renderer while
the parent mixes the sound. Each worker runs ``draw(indices)`` (see :data:`DrawFrames`) over
all frames up to its last one, drawing its own and only *following* the others (the caller's
``draw`` decides what following costs: for a renderer, uploading the frame so its face's
reactions see every frame, as in one process); it sends each of its frames (a numpy array,
or None where the worker wrote the frame itself, a PNG) through a pipe. A thread per worker
in the parent drains its pipe into a queue of about a chunk, so no worker waits on the parent
while it takes another's chunk, and :class:`FrameStream` yields the frames in frame order.

Errors: a worker that fails sends its error's text, and the parent raises it as a
:class:`DisplayError` naming the worker; a worker that dies without a word is reported with
its exit status. Closing the iterator early (an error in the caller, Ctrl-C) ends the workers.

Limits: Linux/Unix only (the fork server); the parent's memory for waiting frames is about
``jobs x (chunk + 2)`` frames.
"""

from __future__ import annotations

import copyreg
import io
import logging
import multiprocessing
import os
import pickle
import queue
import resource
import threading
from collections.abc import Callable, Iterator
from types import MappingProxyType
from typing import Any

import numpy as np

from livedrummer.render.frame_split import (
    DEFAULT_CHUNK,
    default_jobs,
    owner_of,
    threads_per_worker,
    usable_cores,
    worker_frames,
)

from .context import DisplayError

log = logging.getLogger("livedrummer.render")

#: draw(wanted) -> one item per frame index from 0 up to wanted[-1], in order: for an index in
#: ``wanted`` the frame (array) or None (written by the worker itself), for any other index
#: the value is ignored (the worker only followed that frame)
DrawFrames = Callable[[np.ndarray], Iterator[np.ndarray | None]]

_DONE = "done"
_ERROR = "error"
_FRAME = "frame"


def _proxy(items: dict[Any, Any]) -> MappingProxyType[Any, Any]:
    return MappingProxyType(items)


def payload(draw: DrawFrames) -> bytes:
    """``draw`` pickled for the workers; read-only mappings (a kit's tables) go as dicts and
    come back read-only. A DisplayError names what cannot be sent."""
    out = io.BytesIO()
    pickler = pickle.Pickler(out, protocol=pickle.HIGHEST_PROTOCOL)
    table = copyreg.dispatch_table.copy()
    table[MappingProxyType] = lambda m: (_proxy, (dict(m),))
    pickler.dispatch_table = table
    try:
        pickler.dump(draw)
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise DisplayError(
            f"render workers: cannot send the scene to them ({exc}); use --jobs 1"
        ) from None
    return out.getvalue()


def _work(sent: bytes, wanted: np.ndarray, conn: Any, threads: int) -> None:
    """A worker: set llvmpipe's threads, then draw and send its frames."""
    os.environ.setdefault("LP_NUM_THREADS", str(threads))
    try:
        draw: DrawFrames = pickle.loads(sent)
        mine = set(wanted.tolist())
        for index, image in enumerate(draw(wanted)):
            if index in mine:
                conn.send((_FRAME, image))
        usage = resource.getrusage(resource.RUSAGE_SELF)
        conn.send((_DONE, (len(mine), usage.ru_utime + usage.ru_stime)))
    except KeyboardInterrupt:  # the parent got it too and ends the render
        pass
    except Exception as exc:  # sent to the parent, which raises it on its own thread
        try:
            conn.send((_ERROR, f"{type(exc).__name__}: {exc}" if not str(exc) else str(exc)))
        except OSError:
            pass
    finally:
        conn.close()


def _drain(conn: Any, into: queue.Queue[tuple[str, Any]], stop: threading.Event) -> None:
    """The parent's reader for one worker: its pipe into its queue, until done or told."""
    while not stop.is_set():
        try:
            item = conn.recv()
        except (EOFError, OSError):
            item = (_ERROR, None)
        while not stop.is_set():
            try:
                into.put(item, timeout=0.1)
                break
            except queue.Full:
                continue
        if item[0] != _FRAME:
            return


class FrameStream:
    """Frames 0..frames-1 in order, from forked workers (:meth:`fork`) or drawn in this
    process (:meth:`here`); iterate once, then :meth:`close` (also after an error)."""

    def __init__(self, frames: int, chunk: int = DEFAULT_CHUNK) -> None:
        self.frames = frames
        self.chunk = chunk
        self._draw: DrawFrames | None = None
        self._procs: list[Any] = []
        self._queues: list[queue.Queue[tuple[str, Any]]] = []
        self._readers: list[threading.Thread] = []
        self._stop = threading.Event()
        #: each worker's CPU seconds (user + system), once every frame has been taken
        self.cpu_s: list[float] = []

    @classmethod
    def here(cls, draw: DrawFrames, frames: int) -> FrameStream:
        """Drawn in this process when iterated (one renderer, every frame its own)."""
        stream = cls(frames)
        stream._draw = draw
        return stream

    @classmethod
    def fork(
        cls,
        draw: DrawFrames | bytes,
        frames: int,
        jobs: int,
        threads: int,
        chunk: int = DEFAULT_CHUNK,
    ) -> FrameStream:
        """``jobs`` workers forked now (``threads`` llvmpipe threads each), drawing at once;
        ``draw`` or its :func:`payload`."""
        stream = cls(frames, chunk)
        sent = draw if isinstance(draw, bytes) else payload(draw)
        ctx = start_server()
        pipes = []
        try:
            for k in range(jobs):
                wanted = worker_frames(frames, jobs, k, chunk)
                if not wanted.size:
                    break
                mine, theirs = ctx.Pipe(duplex=False)
                proc = ctx.Process(
                    target=_work,
                    args=(sent, wanted, theirs, threads),
                    name=f"render-{k}",
                    daemon=True,
                )
                proc.start()
                theirs.close()
                stream._procs.append(proc)
                pipes.append(mine)
            for k, conn in enumerate(pipes):
                q: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=chunk + 2)
                reader = threading.Thread(
                    target=_drain,
                    args=(conn, q, stream._stop),
                    name=f"render-{k}-pipe",
                    daemon=True,
                )
                reader.start()
                stream._queues.append(q)
                stream._readers.append(reader)
        except BaseException:
            stream.close()
            raise
        return stream

    @property
    def workers(self) -> int:
        return len(self._procs)

    def __iter__(self) -> Iterator[np.ndarray | None]:
        if self._draw is not None:
            yield from self._draw(np.arange(self.frames, dtype=np.int64))
            return
        jobs = len(self._procs)
        for i in range(self.frames):
            k = owner_of(i, jobs, self.chunk)
            kind, value = self._queues[k].get()
            if kind == _FRAME:
                yield value
                continue
            if kind == _DONE:
                value = f"finished before frame {i}"
            elif value is None:
                self._procs[k].join(timeout=5.0)
                value = f"exited with status {self._procs[k].exitcode} before frame {i}"
            raise DisplayError(f"render worker {k}: {value}")
        self._report()

    def _report(self) -> None:
        """Log each worker's frames and CPU seconds (``-v``): how busy the cores were."""
        for k, q in enumerate(self._queues):
            try:
                kind, value = q.get(timeout=5.0)
            except queue.Empty:
                continue
            if kind == _DONE:
                frames, cpu_s = value
                self.cpu_s.append(cpu_s)
                log.info("render worker %d: %d frames, %.2f s of CPU", k, frames, cpu_s)

    def close(self) -> None:
        """End the workers (at once if they are still drawing) and their readers."""
        self._stop.set()
        for proc in self._procs:
            if proc.is_alive():
                proc.terminate()
        for proc in self._procs:
            proc.join(timeout=5.0)
        for reader in self._readers:
            reader.join(timeout=1.0)


#: what the fork server imports once, so that each worker it forks starts with them loaded
PRELOAD = ["services.display.export", "services.display.stage_export"]


def start_server() -> Any:
    """The fork server's multiprocessing context, the server started (at most once a process):
    call it early to overlap its start-up (a fresh interpreter importing :data:`PRELOAD`)
    with other work."""
    from multiprocessing import forkserver

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(PRELOAD)
    forkserver.ensure_running()
    return ctx


def frame_stream(
    draw: DrawFrames, frames: int, jobs: int | None, chunk: int = DEFAULT_CHUNK
) -> FrameStream:
    """``jobs`` workers (None: :func:`~livedrummer.render.frame_split.default_jobs` for this
    machine's cores) drawing ``frames`` frames; one worker draws here, in this process. With
    ``jobs`` None a scene that cannot be sent to workers (:func:`payload`) is drawn here, and
    a warning says why; asked for workers, the DisplayError says it."""
    cores = usable_cores()
    count = default_jobs(cores, frames, chunk) if jobs is None else min(jobs, max(1, frames))
    if count > 1:
        try:
            sent = payload(draw)
        except DisplayError as exc:
            if jobs is not None:
                raise
            log.warning("%s; drawing in this process", exc)
        else:
            return FrameStream.fork(sent, frames, count, threads_per_worker(cores, count), chunk)
    return FrameStream.here(draw, frames)
