"""The input daemon: one source in, onsets and controls out on ZeroMQ, every batch journaled.

Threads and sockets. The main thread owns the source and the XPUB socket: it reads the source
(blocking at most ``read_timeout_s``), publishes each batch and journals it, so a serial or
file event is never queued between arrival and publication (MIDI ports are drained from
rtmidi's own queue by this thread, each message stamped with the driver's time: see
:mod:`services.input.midiport`). XPUB instead of PUB so the daemon *sees* subscriptions arrive: with
``wait_subscribers`` it opens its source only after that many subscriptions arrived (a SUB
socket subscribed to k topics counts k), which is how a launcher or a test gets every event
from the first one without sleeping. Start-up, the control socket (a second thread answering
HELLO with READY: service "input", role "source", performer, endpoints, so a client can wait
for the daemon instead of guessing), readiness (once bound) and shutdown are the service
base's (:mod:`services.process.service`); :meth:`InputDaemon.open` binds the pub socket and opens
the journal, :meth:`InputDaemon.release` closes the source, the journal (END record with the
summary) and the socket.

Stream. Every message on the events stream (ONSET, CONTROL, GAP, HEARTBEAT) takes the next
sequence number, so a subscriber's :class:`~livedrummer.protocol.SequenceTracker` sees any
loss, including at the tail (heartbeats every ``heartbeat_s``). A batch is published as runs
of one kind in arrival order. Each batch is journaled (one ``write``, into the page cache)
*before* it is published, so whatever a subscriber has seen survives a kill -9 of the daemon;
this costs the publication one system call (~10 µs).

Faults. A device that is absent or fails is closed and reopened every ``reconnect_s``; when it
returns, a GAP (reason SOURCE_LOST, dropped 0: unknown) spans the outage. Device errors, bad
remote messages, unmapped notes and journal write errors are logged once per kind and
counted; the counts go to the log and into the journal's END record at shutdown. Bad
messages on the control socket (and, for a remote source, on its SUB socket) are counted per
kind by :class:`~services.wire.badmsg.BadMessages` (``bad_control``; ``summary()["bad_messages"]``).
The daemon keeps running through all of them.

Load and shedding. The daemon holds no queue of its own on the serial and file paths: the main
thread reads what the device delivered, journals it and publishes it, so a flood backs up in
the device (a tty's bounded kernel buffer; a real UART at 31,250 baud cannot flood at all)
and never in our memory. The rtmidi path has one bounded queue, rtmidi's own (see
:mod:`services.input.midiport`: 65,536 messages, drained every 0.5 ms). Publication never
blocks: past the high-water mark (``services.wire.net.DEFAULT_HWM`` messages per subscriber)
ZeroMQ drops messages for that slow subscriber only, which it sees as a sequence gap; every
event was journaled before it was offered to ZeroMQ, so the journal stays complete.
``services/bench/flood.py`` measures this at 10,000 notes/s.

Security. With ``config.security`` holding a key pair, both sockets are CURVE servers; with
an allow folder, a ZAP authenticator (started and stopped by the service base) lets in only the
clients whose public keys are there (see :mod:`services.wire.net`).
"""

from __future__ import annotations

import logging
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import zmq

from livedrummer.errors import JournalError, MidiInputError, ProtocolError
from livedrummer.protocol import (
    Flag,
    Gap,
    GapReason,
    Hello,
    Kind,
    Message,
    Stream,
    encode,
)
from livedrummer.protocol.journal import SUFFIX as JOURNAL_SUFFIX
from livedrummer.timeline.clock import Clock
from livedrummer.timeline.events import CONTROL_DTYPE, ONSET_DTYPE, Control, Onset

from ..process.service import OnReady, Service
from ..wire.net import Security, bind, socket
from .base import Event, Source
from .journal import JournalWriter, new_session_id, sessions_dir
from .remote import RemoteSource

#: While the source is absent, one status line this often (seconds).
STATUS_S = 5.0

log = logging.getLogger("livedrummer.input")

DEFAULT_PUB = "tcp://127.0.0.1:5710"
DEFAULT_CONTROL = "tcp://127.0.0.1:5711"


@dataclass
class DaemonConfig:
    pub: str = DEFAULT_PUB
    control: str = DEFAULT_CONTROL
    performer: int = 0
    wait_subscribers: int = 0
    exit_at_end: bool = False
    heartbeat_s: float = 1.0
    reconnect_s: float = 0.1  # try an absent device this often: replugged -> serving in ~0.1 s
    read_timeout_s: float = 0.02
    journal: bool = True
    sessions_dir: Path | None = None
    fsync_interval_s: float = 1.0
    meta: dict[str, Any] = field(default_factory=dict)
    security: Security = field(default_factory=Security)


@dataclass
class DaemonStats:
    messages: int = 0
    onsets: int = 0
    controls: int = 0
    gaps: int = 0
    heartbeats: int = 0
    subscribers: int = 0


class InputDaemon(Service):
    """See the module docstring. ``start`` binds; ``run`` serves until ``stop`` is set."""

    name = "input"

    def __init__(
        self,
        source: Source,
        config: DaemonConfig,
        clock: Clock,
        ctx: zmq.Context[zmq.Socket[bytes]],
    ) -> None:
        super().__init__(
            clock,
            ctx,
            performer=config.performer,
            security=config.security,
            control=config.control,
            log=log,
        )
        self.clock: Clock = clock
        self.source = source
        self.config = config
        self.problems = source.problems
        self.stats = DaemonStats()
        self.journal: JournalWriter | None = None
        self._flags = (Flag.SIMULATED if source.simulated else 0) | (
            Flag.RELAYED if source.relayed else 0
        )
        self._seq = 0
        self._last_send = 0.0
        self._pub: Any = None
        self._unknown_seen = 0
        self._session: str | None = None  # the journal's name, planned at start

    # ---------------------------------------------------------------- lifecycle

    def open(self) -> None:
        """Bind the pub socket and open the journal (the base binds the control socket)."""
        cfg = self.config
        self._pub = socket(self.ctx, zmq.XPUB)
        self._pub.setsockopt(zmq.XPUB_VERBOSE, 1)
        self.endpoints["pub"] = bind(self._pub, cfg.pub, "pub endpoint", cfg.security)
        if cfg.journal:  # named now, created once the source has opened (no empty sessions)
            folder = cfg.sessions_dir if cfg.sessions_dir is not None else sessions_dir()
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise JournalError(
                    f"{folder}: cannot create journal: {exc.strerror or exc}"
                ) from None
            if not os.access(folder, os.W_OK):
                raise JournalError(f"{folder}: cannot create journal: folder not writable")
            self._session = new_session_id(cfg.performer)
            self.endpoints["journal"] = str(folder / f"{self._session}{JOURNAL_SUFFIX}")

    def _open_journal(self) -> None:
        cfg = self.config
        meta = {
            "performer": cfg.performer,
            "source": self.source.name,
            "protocol_endpoints": {k: v for k, v in self.endpoints.items() if k != "journal"},
            **cfg.meta,
        }
        self.journal = JournalWriter.create(
            meta,
            self.clock,
            cfg.sessions_dir,
            session_id=self._session,
            fsync_interval_s=cfg.fsync_interval_s,
        )

    def hello(self) -> Hello:
        return Hello(self.name, "source", self.config.performer, dict(self.endpoints))

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        """Serve until ``stop`` (or the end of a file with ``exit_at_end``); ready once bound."""
        cfg = self.config
        src = self.source
        lost_at: float | None = None
        waiting_since: float | None = None  # the source is absent since (status every 5 s)
        next_status = 0.0
        if on_ready is not None:
            on_ready()  # serving: subscribers get every event from their subscription on
        try:
            while not stop.is_set():
                self._poll_subscribers(0)
                if self.clock.now() - self._last_send >= cfg.heartbeat_s:
                    self._send(Kind.HEARTBEAT, None)
                if not src.is_open:
                    if self.stats.subscribers < cfg.wait_subscribers:
                        self._poll_subscribers(int(cfg.read_timeout_s * 1000))
                        continue
                    try:
                        src.open()
                    except MidiInputError as exc:
                        self.problems.report("source unavailable", str(exc))
                        now = self.clock.now()
                        waiting_since = now if waiting_since is None else waiting_since
                        if now >= next_status:
                            if now > waiting_since:  # the first failure was logged just now
                                log.warning(
                                    "%s: still waiting (%.0f s): %s",
                                    src.name,
                                    now - waiting_since,
                                    exc,
                                )
                            next_status = now + STATUS_S
                        stop.wait(cfg.reconnect_s)
                        continue
                    if waiting_since is not None:
                        log.warning(
                            "%s: connected after %.1f s", src.name, self.clock.now() - waiting_since
                        )
                        waiting_since = None
                    log.info("%s: connected", src.name)
                    if self.journal is None and self._session is not None:
                        self._open_journal()
                    if lost_at is not None:
                        self.publish([Gap(0, lost_at, self.clock.now(), GapReason.SOURCE_LOST)])
                        lost_at = None
                try:
                    events = src.read(cfg.read_timeout_s)
                except MidiInputError as exc:
                    log.warning("source lost: %s; reconnecting", exc)
                    self.problems.counts["source lost"] += 1
                    src.close()
                    lost_at = self.clock.now()
                    continue
                if events:
                    self.publish(events)
                if cfg.exit_at_end and src.finished():
                    break
        finally:
            self.shutdown()
        return 0

    def release(self) -> None:
        self.source.close()
        summary = self.summary()
        if self.journal is not None:
            try:
                self.journal.close(summary)
            except JournalError as exc:
                log.error("%s", exc)
            self.journal = None
        if self._pub is not None:
            self._pub.close(0)
            self._pub = None
        if isinstance(self.source, RemoteSource):
            self.source.bad.log_summary()
        log.info("input stopped: %s", summary)

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "messages": self.stats.messages,
            "onsets": self.stats.onsets,
            "controls": self.stats.controls,
            "gaps": self.stats.gaps,
            "problems": self.problems.summary(),
            "bad_messages": self.bad_messages(),
        }
        if isinstance(self.source, RemoteSource) and (timing := self.source.timing()):
            out["remote_timing"] = timing
        d = self.source.decode_stats()
        if d is not None:
            out["unknown_notes"] = {str(k): v for k, v in sorted(d.unknown_notes.items())}
            out["duplicates_removed"] = d.duplicates_removed
            out["ignored"] = dict(d.ignored)
        return out

    def bad_messages(self) -> dict[str, dict[str, int]]:
        """Dropped network messages by socket and kind (only sockets that dropped some)."""
        out = {"control": self.bad_control.summary()}
        if isinstance(self.source, RemoteSource):
            out["remote"] = self.source.bad.summary()
        return {k: v for k, v in out.items() if v}

    # ---------------------------------------------------------------- publishing

    def publish(self, events: list[Event]) -> None:
        arrival = self.clock.now()
        i, n = 0, len(events)
        while i < n:
            first = events[i]
            if isinstance(first, Gap):
                if self._send(Kind.GAP, first, "append_gap", arrival) >= 0:
                    self.stats.gaps += 1
                i += 1
                continue
            kind = type(first)
            j = i + 1
            while j < n and type(events[j]) is kind:
                j += 1
            run = events[i:j]
            if kind is Onset:
                rows = np.array([e.to_record() for e in run], dtype=ONSET_DTYPE)  # type: ignore[union-attr]
                if self._send(Kind.ONSET, rows, "append_onsets", arrival) >= 0:
                    self.stats.onsets += len(run)
            elif kind is Control:
                rows = np.array([e.to_record() for e in run], dtype=CONTROL_DTYPE)  # type: ignore[union-attr]
                if self._send(Kind.CONTROL, rows, "append_controls", arrival) >= 0:
                    self.stats.controls += len(run)
            i = j
        self._check_unknown_notes()

    def _send(
        self,
        kind: Kind,
        body: np.ndarray | Gap | None,
        journal: str | None = None,
        arrival: float = 0.0,
    ) -> int:
        """Journal (when ``journal`` names the writer method), stamp, encode, publish.

        Returns the sequence number, or -1 if the message could not be encoded.
        """
        seq = self._seq
        if journal is not None:
            self._journal(journal, body, arrival, seq)
        now = self.clock.now()
        msg = Message(kind, body, self.config.performer, seq, now, Stream.EVENTS, int(self._flags))
        try:
            frames = encode(msg)
        except ProtocolError as exc:  # the decoders only make valid rows; kept as a guard
            self.problems.report("unencodable event", str(exc))
            return -1
        self._pub.send_multipart(frames, copy=False)
        self._seq = seq + 1
        self._last_send = now
        self.stats.messages += 1
        if kind is Kind.HEARTBEAT:
            self.stats.heartbeats += 1
        return seq

    def _journal(self, method: str, body: Any, arrival: float, seq: int) -> None:
        if self.journal is None:
            return
        try:
            getattr(self.journal, method)(body, arrival, seq)
        except JournalError as exc:
            self.problems.report("journal write failed", str(exc))

    def _check_unknown_notes(self) -> None:
        stats = self.source.decode_stats()
        if stats is None:
            return
        unknown = stats.unknown_notes
        if len(unknown) > self._unknown_seen:
            self._unknown_seen = len(unknown)
            notes = ", ".join(str(k) for k in sorted(unknown))
            log.warning("notes not in the note map (ignored): %s", notes)

    def _poll_subscribers(self, timeout_ms: int) -> None:
        pub = self._pub
        if timeout_ms and not pub.poll(timeout_ms):
            return
        while True:
            try:
                frame = pub.recv(zmq.NOBLOCK)
            except zmq.Again:
                return
            if frame[:1] == b"\x01":
                self.stats.subscribers += 1
            elif frame[:1] == b"\x00":
                self.stats.subscribers = max(0, self.stats.subscribers - 1)

    # ---------------------------------------------------------------- control socket

    def control_dropped(self, kind: str) -> None:
        # Totals in the problems report too, which goes into the journal's END record.
        what = "unexpected control message" if kind == "unexpected" else "bad control message"
        self.problems.counts[what] += 1
