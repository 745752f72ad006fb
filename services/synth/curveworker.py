"""The synth's curves in a worker process: re-animation and sampling off the answering process.

Why this shape. Profiled live (``docs/synth.md``), a hit's answer costs 1.5-2.5 ms of CPU but
takes several times that, with tails of tens of milliseconds, because the synth's animation
thread holds the interpreter (the GIL) while it re-animates the window (3-44 ms per hit) and
samples the strokes (2-33 ms): the answer thread gets it back only at the switch interval,
between the animation's numpy calls. :class:`CurveWorker` is a
:class:`~livedrummer.live.curves.CurveSource` whose :class:`~livedrummer.live.curves.CurveSet`
lives in a child process (``python -m services.synth.curveworker`` on a socket pair: nothing
of the service's threads or sockets is inherited, and unlike ``multiprocessing``'s spawn it
does not import the parent's main module again). The animation thread sends a request over
the socket and blocks on the reply, in a system call with the GIL let go, so the answer
thread runs whenever a hit arrives; the operating system shares the cores between the two
processes, not the interpreter. What the child computes is what the in-process set would
have (the same code on the same pickled inputs): the strokes replace the quick contacts as before.

The protocol. One request at a time, answered before the next is sent (the queue is bounded
by construction: the animation thread waits for each reply): ``("rebuild", arguments)``,
``("sample", times)`` and ``("reset",)``; the reply is ``("ok", payload)`` or ``("error",
text)``. A request the child cannot carry out (a bad message, an exception in the body's
code) is answered with an error and the child carries on; the parent raises
:class:`CurveWorkerError` with the child's text. Kits hold read-only mappings
(``MappingProxyType``), which the standard pickler refuses; both sides pickle with a table
that sends them as plain dicts and rebuilds them.

Failure. If the child dies (killed, out of memory) or does not answer within ``timeout_s``,
it is killed and a new one is started; the last rebuild is sent again, so a sample request
finds the same curves (the cross-fade that was under way and the clearance memo are lost:
the next strokes may differ by as much as a fresh synth's), and the request is retried once.
A restart is logged and counted (:attr:`CurveWorker.restarts`). Limits: one request's
round trip is added to every re-animation and sampling: pickling takes 0.2 ms (7 KB of
window out, 25 KB of samples back), but the child must also be woken and given a core: on
the loaded 2-core machine (load average 16) a re-animation took 40.7 ms p50 through the
worker against 33.2 in process, a sampling of 20 times 25.4 against 24.2 (waits with the
GIL free); a quick contact cannot sample the worker's curves (:meth:`CurveWorker.view` is
empty), so before the first samples there is none; the child takes about a second to start
(its imports), done once in :meth:`CurveWorker.start`.
"""

from __future__ import annotations

import copyreg
import io
import logging
import os
import pickle
import signal
import socket
import subprocess
import sys
from dataclasses import dataclass
from multiprocessing.connection import Connection
from types import MappingProxyType, TracebackType
from typing import Any

import numpy as np

from livedrummer.body.animation import Openness
from livedrummer.body.expression import Expression
from livedrummer.body.rig import Rig
from livedrummer.body.strokes import StrokeParams
from livedrummer.errors import LivedrummerError
from livedrummer.live.curves import Answer, CurveSet, CurveView
from livedrummer.live.style import StyleChange
from livedrummer.sticking.result import Sticking

log = logging.getLogger("livedrummer.synth")

#: How long a new worker may take to import and say it is ready.
START_TIMEOUT_S = 60.0


class CurveWorkerError(LivedrummerError):
    """The curve worker could not carry out a request (its message says why)."""


def _mapping_proxy(items: dict[Any, Any]) -> MappingProxyType[Any, Any]:
    return MappingProxyType(items)


def _reduce_proxy(m: MappingProxyType[Any, Any]) -> tuple[Any, tuple[dict[Any, Any]]]:
    return _mapping_proxy, (dict(m),)


def dumps(obj: object) -> bytes:
    """``obj`` pickled, read-only mappings as dicts (see the module docstring)."""
    buf = io.BytesIO()
    pickler = pickle.Pickler(buf, protocol=pickle.HIGHEST_PROTOCOL)
    table = copyreg.dispatch_table.copy()
    table[MappingProxyType] = _reduce_proxy
    pickler.dispatch_table = table
    pickler.dump(obj)
    return buf.getvalue()


def serve(conn: Connection, nice: int) -> None:
    """The child's loop: the set-up (the rig, ``blend_s`` and the stroke parameters, pickled
    by :func:`dumps`) first, then one request in, one reply out, until the pipe closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the service's to handle
    if nice:
        os.nice(nice)
    rig, blend_s, strokes = pickle.loads(conn.recv_bytes())
    curves = CurveSet(rig, blend_s, strokes)
    conn.send_bytes(dumps(("ok", os.getpid())))
    while True:
        try:
            raw = conn.recv_bytes()
        except (EOFError, OSError):
            return
        try:
            reply = ("ok", _handle(curves, pickle.loads(raw)))
        except Exception as exc:  # a bad request: said to the parent, the loop carries on
            reply = ("error", f"{type(exc).__name__}: {exc}")
        conn.send_bytes(dumps(reply))


def _handle(curves: CurveSet, msg: object) -> object:
    if not isinstance(msg, tuple) or not msg:
        raise ValueError(f"expected a request tuple, got {type(msg).__name__}")
    kind = msg[0]
    if kind == "rebuild" and len(msg) == 2 and isinstance(msg[1], dict):
        curves.rebuild(**msg[1])
        return None
    if kind == "sample" and len(msg) == 2 and isinstance(msg[1], np.ndarray):
        return curves.sample(msg[1])
    if kind == "reset" and len(msg) == 1:
        curves.reset()
        return None
    raise ValueError(f"unknown request {kind!r} (of {len(msg)} items)")


@dataclass(frozen=True)
class _Built:
    """What the synth reads of the worker's current curves (a
    :class:`~livedrummer.live.curves.Built`)."""

    key: tuple[object, ...]
    contacts_s: np.ndarray


class CurveWorker:
    """See the module docstring. ``with CurveWorker(...) as curves:`` starts the child and
    stops it; pass it to :class:`~livedrummer.live.synth.LiveSynth` as ``curves``."""

    def __init__(
        self,
        rig: Rig,
        blend_s: float,
        strokes: StrokeParams | None = None,
        *,
        timeout_s: float = 10.0,
        nice: int = 0,
    ) -> None:
        self.rig = rig
        self.blend_s = blend_s
        self.strokes = strokes
        self.timeout_s = timeout_s
        self.nice = nice
        self.restarts = 0  # children started again after one died or hung
        self._proc: subprocess.Popen[bytes] | None = None
        self._conn: Connection | None = None
        self._last_rebuild: bytes | None = None
        self.reset_local()

    # -- lifecycle -----------------------------------------------------------------------------

    def start(self) -> CurveWorker:
        """Start the child and wait until it is ready (its imports take about a second)."""
        mine, theirs = socket.socketpair()
        fd = theirs.fileno()
        proc = subprocess.Popen(
            [sys.executable, "-m", __name__, str(fd), str(self.nice)],
            pass_fds=(fd,),
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
        )
        theirs.close()
        self._proc, self._conn = proc, Connection(mine.detach())
        try:
            self._conn.send_bytes(dumps((self.rig, self.blend_s, self.strokes)))
            ready = self._conn.poll(START_TIMEOUT_S)
            if ready:
                pickle.loads(self._conn.recv_bytes())
        except (EOFError, OSError) as exc:
            self.close()
            raise CurveWorkerError(f"the curve worker died at start ({exc})") from None
        if not ready:
            self.close()
            raise CurveWorkerError(f"the curve worker did not start within {START_TIMEOUT_S:g} s")
        return self

    def close(self) -> None:
        """Stop the child (its pipe closed: it returns; killed if it does not)."""
        conn, proc = self._conn, self._proc
        self._conn = self._proc = None
        if conn is not None:
            conn.close()
        if proc is not None:
            try:
                proc.wait(2.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(2.0)

    def __enter__(self) -> CurveWorker:
        return self.start()

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    @property
    def pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    # -- the CurveSource -----------------------------------------------------------------------

    def reset_local(self) -> None:
        self.animations = 0
        self.built_at = -float("inf")
        self._current: _Built | None = None
        self._last_rebuild = None

    def reset(self) -> None:
        self.reset_local()
        if self._conn is not None:
            self._call(dumps(("reset",)))

    @property
    def current(self) -> _Built | None:
        return self._current

    def view(self) -> CurveView:
        return CurveView(None)  # the curves are the child's (see the module docstring)

    def rebuild(
        self,
        sticking: Sticking,
        beats: np.ndarray,
        openness: Openness,
        key: tuple[object, ...],
        contacts_s: np.ndarray,
        chokes: list[np.ndarray] | None,
        start_s: float,
        horizon_s: float,
        answer: Answer | None = None,
        expression: Expression | None = None,
        change: StyleChange | None = None,
    ) -> None:
        """:meth:`CurveSet.rebuild <livedrummer.live.curves.CurveSet.rebuild>` in the child;
        ``answer`` is not called: the GIL is free while the child works."""
        msg = dumps(
            (
                "rebuild",
                {
                    "sticking": sticking,
                    "beats": beats,
                    "openness": openness,
                    "key": key,
                    "contacts_s": contacts_s,
                    "chokes": chokes,
                    "start_s": start_s,
                    "horizon_s": horizon_s,
                    "expression": expression,
                    "change": change,
                },
            )
        )
        self._call(msg, replay=False)
        self._last_rebuild = msg
        self.animations += 1
        self.built_at = horizon_s
        self._current = _Built(key, contacts_s)

    def sample(self, times: np.ndarray, answer: Answer | None = None) -> np.ndarray:
        """:meth:`CurveSet.sample <livedrummer.live.curves.CurveSet.sample>` in the child."""
        rows = self._call(dumps(("sample", np.asarray(times, dtype=np.float64))))
        if not isinstance(rows, np.ndarray):
            raise CurveWorkerError(f"the curve worker sent {type(rows).__name__}, not samples")
        return rows

    # -- the pipe ------------------------------------------------------------------------------

    def _call(self, msg: bytes, replay: bool = True) -> object:
        """Send one request and return the reply's payload; a dead or hung child is
        restarted (with the last rebuild sent again when ``replay``) and the request retried
        once."""
        if self._conn is None:
            self.start()
        reply = self._exchange(msg)
        if isinstance(reply, str):
            self._restart(reply)
            if replay and self._last_rebuild is not None:
                again = self._exchange(self._last_rebuild)
                if isinstance(again, str) or again[0] != "ok":
                    raise CurveWorkerError(f"the restarted curve worker failed: {again}")
            reply = self._exchange(msg)
            if isinstance(reply, str):
                raise CurveWorkerError(f"the curve worker failed twice: {reply}")
        status, payload = reply
        if status != "ok":
            raise CurveWorkerError(f"curve worker: {payload}")
        return payload

    def _exchange(self, msg: bytes) -> tuple[str, object] | str:
        """The reply to ``msg``, or why there is none (the child died or hung)."""
        conn = self._conn
        if conn is None:
            return "not running"
        try:
            conn.send_bytes(msg)
            if not conn.poll(self.timeout_s):
                return f"no reply within {self.timeout_s:g} s"
            reply = pickle.loads(conn.recv_bytes())
        except (EOFError, OSError) as exc:
            proc = self._proc
            code = None if proc is None else proc.poll()
            return f"it died ({type(exc).__name__}, exit code {code})"
        if not (isinstance(reply, tuple) and len(reply) == 2 and isinstance(reply[0], str)):
            return f"a reply of the wrong shape ({type(reply).__name__})"
        return reply

    def _restart(self, why: str) -> None:
        proc = self._proc
        if proc is not None and proc.poll() is None:
            proc.kill()
        self.close()
        self.restarts += 1
        log.warning(
            "synth: the curve worker stopped answering (%s); restarted (%d so far), "
            "the cross-fade under way is lost",
            why,
            self.restarts,
        )
        self.start()


def main(argv: list[str]) -> int:
    """The child's entry (``python -m services.synth.curveworker FD NICE``): serve on the
    socket ``FD`` the parent passed."""
    serve(Connection(int(argv[0])), int(argv[1]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
