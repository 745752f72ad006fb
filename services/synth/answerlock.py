"""The synth service's lock, with the answer thread first in line.

Why this shape. The synth's two threads (see :mod:`services.synth.service`) share the live
synth under one lock. A plain :class:`threading.Lock` is not fair: the animation thread lets
it go for a re-animation step and takes it back at once, often before the answer thread,
woken, gets to it; at 100 notes a second, where the animation thread ticks back to back, a
hit then waited for many steps (answers of a second were measured). Here the answer thread
says it wants the lock before it waits for it (:meth:`AnswerFirstLock.answering`), and the
animation thread's :meth:`~AnswerFirstLock.acquire` first waits until no answer is wanted or
under way: a hit waits for at most the one step the animation thread is in.

:meth:`~AnswerFirstLock.wait_answered` is what the animation thread calls between its steps
while it does not hold the lock (``LiveSynth.poses_until(answer=...)``): it waits while a
hit is being answered, so the two threads do not share the interpreter for long. Limits: one
answering thread (the wish is a flag, not a count); the animation thread must not call
:meth:`~AnswerFirstLock.wait_answered` while it holds the lock (the answer thread may be
waiting for it: each would wait for the other).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import TracebackType


class AnswerFirstLock:
    """See the module docstring. ``with lock:`` and :meth:`acquire`/:meth:`release` are the
    animation thread's; :meth:`answering` is the answer thread's."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._free = threading.Event()  # set: no answer wanted or under way
        self._free.set()

    def acquire(self) -> bool:
        self._free.wait()
        return self._lock.acquire()

    def release(self) -> None:
        self._lock.release()

    def __enter__(self) -> AnswerFirstLock:
        self.acquire()
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.release()

    @contextmanager
    def answering(self) -> Iterator[None]:
        """Hold the lock ahead of the animation thread, for one answer."""
        self._free.clear()
        try:
            with self._lock:
                yield
        finally:
            self._free.set()

    @property
    def wanted(self) -> bool:
        """Whether an answer is wanted or under way."""
        return not self._free.is_set()

    def wait_answered(self) -> None:
        """Wait while an answer is wanted or under way (never while holding the lock)."""
        self._free.wait()
