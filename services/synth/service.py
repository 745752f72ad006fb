"""The synth service: subscribes to an input daemon, publishes pose samples on show time.

One thread owns the SUB (events in) and PUB (poses out) sockets: it waits on the SUB socket
until the next tick, feeds every ONSET and CONTROL row to the
:class:`~livedrummer.live.synth.LiveSynth` as it arrives, and at each tick (``tick_hz``, default
120, as soon as a note's limb is due to be committed, and at once when an onset arrives)
publishes whatever samples the synth has for show times up to ``now + D`` (with provisional
poses, the default; ``now + D - L`` without), as one POSE message (header time = the first
sample's show time; each record's ``time_s`` is its offset from it). Each batch of onsets read
(up to :data:`DRAIN_BATCH` messages) has its quick contacts published before anything else
(``LiveSynth.take_quick``).

Two threads: nothing blocks the answer. The *answer* thread (the one ``run`` is called in)
waits on the SUB socket and answers every hit the moment it is read: forward, the note into
the window, its quick contact solved and published (about a millisecond). The *animation*
thread ticks: re-animates the window and samples the strokes between the contacts
(``LiveSynth.poses_until``, 10-50 ms when the notes changed). Both work on the synth under
one lock, which the animation thread lets go for the long steps (``poses_until(lock=...)``:
while the curves are rebuilt and sampled, from a copy of what they read), so a hit waits for
at most one short book-keeping step, never for a re-animation. The GIL's switch interval
is set to :data:`SWITCH_S` while the service runs, so the answer thread, woken by its
socket, takes the interpreter from a busy animation thread within that long; and between
its steps (``poses_until(answer=...)``) a re-animation waits while a hit is being answered,
so the two share the interpreter only until the re-animation's next step. The PUB socket
is used by both threads, only ever under the lock (a ZeroMQ socket may pass between threads
behind a full memory barrier), so batches leave in the order they were cut. The lock lets
the answer thread go first (:class:`~services.synth.answerlock.AnswerFirstLock`): a plain
lock let the animation thread, taking it back between its steps, starve the answers at 100
notes a second.
``livedrummer synth`` gives the synth a curve worker (:mod:`services.synth.curveworker`): the
re-animation and the sampling then run in a child process, and the animation thread waits
for them in a system call with the GIL let go, so the answer thread no longer shares the
interpreter with them (``--curves-in-process`` keeps them on the thread, for comparison).
Each onset is also forwarded on the pose socket the moment it is read, before the synth
works on it, as a SHOWN_ONSET message stamped with its show time (onset + D): a display sounds
it then (``display --live --sound``), a score strip can draw it. Each control (a cymbal grab,
the hi-hat pedal) is forwarded likewise as SHOWN_CONTROL, so the display's sound stops a
grabbed cymbal or a closing hi-hat at the show time the picture's stops (an ensemble copy's
``vary`` shift is not applied to controls: a grab stays where it was played).
The input stream is read by the one :class:`~services.wire.stream_rx.StreamReceiver`: its sequence
numbers follow :mod:`livedrummer.protocol.sequence` (a gap upstream is counted in ``missing``
and logged, a restarted input daemon is taken, a duplicate dropped). The
service base (:mod:`services.process.service`) runs the control socket (a second thread answering
HELLO with READY; the READY carries the pose format, which a display checks against its own),
start-up and shutdown; the synth tells a launcher or systemd it is ready once its first poses are
published (it is ready when it does its job, not when its sockets are bound).

Bad input. Every message on the SUB socket (subscribed to the protocol magic, so another
protocol version is seen, not filtered away) and on the control socket is decoded and
checked; a bad one is dropped, counted per kind (``bad_events``, ``bad_control``:
:class:`~services.wire.badmsg.BadMessages`, logged once per kind, totals logged at exit and in
``summary()["bad_messages"]``) and the loop carries on with the next message.

Show control. With ``config.osc_port`` the loop also reads an OSC port
(:mod:`services.show.osc`) before each tick: a preset, a parameter or a cue changes the style
(eased in, :mod:`livedrummer.live.style`), ``/livedrummer/state`` is answered with the preset,
every parameter and the performer's state. A cue list's ``bar`` cues fire when the beat
tracker (:mod:`livedrummer.live.beat`) hears their bar start
(:class:`~livedrummer.live.cues.BarCues`), :data:`BAR_LEAD_S` before its predicted start: the
synth eases in their style from the bar's start, and sends their camera and blackout on the
pose stream as a STAGE_CUE message stamped with the bar's show time (its start + D), which
every display applies in the frame that shows that time.

Limits: the pose socket is a plain PUB (a slow display loses samples past the high-water
mark; it sees the gap in the sequence numbers); one performer per synth.

Security: ``config.security`` with a key pair makes the pose and control sockets CURVE
servers (an allow folder starts a ZAP authenticator, stopped at shutdown); with the input
daemon's public key too, the SUB socket is a CURVE client of it (see :mod:`services.wire.net`).
"""

from __future__ import annotations

import logging
import math
import sys
import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zmq

from livedrummer.live.behind import BehindCounter
from livedrummer.live.cues import BarCues, Cue, stage_cue_rows
from livedrummer.live.synth import LiveSynth, PoseBatch
from livedrummer.protocol import (
    Hello,
    Kind,
    Message,
    Pose,
    PoseFormat,
    Stream,
    encode,
)
from livedrummer.stage.variation import Variation, vary_live
from livedrummer.timeline.clock import Clock

from ..process.service import OnReady, Service
from ..show.osc import CUE, PREFIX, STATE, SYNTH_ADDRESSES, Command, OscEndpoint, state_pairs
from ..wire.net import Security, bind, socket
from ..wire.stream_rx import StreamReceiver
from .answerlock import AnswerFirstLock

log = logging.getLogger("livedrummer.synth")

DEFAULT_SUB = "tcp://127.0.0.1:5710"
_EVENT_KINDS = (Kind.ONSET, Kind.CONTROL, Kind.GAP, Kind.HEARTBEAT)
DEFAULT_PUB = "tcp://127.0.0.1:5720"
DEFAULT_CONTROL = "tcp://127.0.0.1:5721"
DRAIN_BATCH = 64  # input messages read before their quick contacts are published
#: A bar cue fires this long before the beat tracker's predicted start of its bar, so that its
#: stage cue reaches a display that draws ahead of the synth (its render-ahead lead can be
#: longer than D) before the frame that shows the bar; its style still eases in on the bar.
BAR_LEAD_S = 0.2
#: The interpreter's switch interval while the service runs (Python's default is 5 ms): the
#: longest an answer waits for the animation thread to hand over the GIL.
SWITCH_S = 0.0005
#: How often the answer thread looks up from its socket (OSC commands, stop, ready).
POLL_MS = 5


@dataclass
class SynthConfig:
    sub: str = DEFAULT_SUB
    pub: str = DEFAULT_PUB
    control: str = DEFAULT_CONTROL
    performer: int = 0
    tick_hz: float = 120.0
    input_offset_s: float = 0.0
    security: Security = field(default_factory=Security)
    avatar: str = ""  # digest of the avatar whose proportions the rig has, announced in READY
    osc_port: int | None = None  # OSC show control (services.show.osc): preset, param, state
    osc_allow: tuple[str, ...] = ()  # OSC senders besides loopback
    preset: str = "neutral"  # the expression's name, for the state reply
    cues: dict[str, Cue] = field(default_factory=dict)  # fired by OSC /livedrummer/cue
    # an ensemble copy's live variation (livedrummer.stage.variation.vary_live), bounded by
    # the caller to D - L; None plays the onsets as they come
    vary: Variation | None = None


@dataclass
class SynthStats:
    onsets: int = 0
    controls: int = 0
    missing: int = 0
    bad: int = 0
    pose_messages: int = 0
    pose_samples: int = 0
    forwarded: int = 0  # onsets forwarded to displays (SHOWN_ONSET)
    forwarded_controls: int = 0  # controls forwarded to displays (SHOWN_CONTROL)
    stage_cues: int = 0  # bar cues' cameras and blackouts sent to displays (STAGE_CUE)
    first_seq: int | None = None
    last_seq: int | None = None
    # read -> quick contacts sent, per batch (the latest ones: a show runs for hours)
    answer_s: deque[float] = field(default_factory=lambda: deque(maxlen=10_000))


class SynthService(Service):
    """See the module docstring. ``start`` binds and connects; ``run`` serves until ``stop``."""

    name = "synth"

    def __init__(
        self,
        synth: LiveSynth,
        config: SynthConfig,
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
        self.synth = synth
        self.config = config
        self.format = PoseFormat.from_dtype(synth.dtype)
        self.stats = SynthStats()
        self.rx = StreamReceiver("synth input stream", log, _EVENT_KINDS)
        self.bad_events = self.rx.bad
        self._pub: Any = None
        self._seq = 0
        self.late = BehindCounter(
            "contacts published after their show time",
            "measured on this machine: it answered those hits later than the show delay "
            "(--delay-ms), so the drummer reached them late on screen; the sound is on time",
        )
        self.merged = BehindCounter(
            "notes merged into another stroke (three hand notes within the chord window: "
            "shown as a flam or double stroke of the nearer hand)",
            "notes that close together, or stamped together by a loaded machine, cannot be "
            "separate strokes of two hands",
            window_s=1.0,
        )
        self._merged_seen = 0  # the window's merged notes already counted
        self._ticked = 0  # onsets heard when the last tick began
        self.osc: OscEndpoint | None = None
        self.preset = config.preset
        self._last_onset_s = -math.inf
        self.bar_cues = BarCues(config.cues)  # the list's bar cues, fired as bars are heard
        self._bars_from = -math.inf
        self._lock = AnswerFirstLock()  # the synth and the PUB socket (see the module docstring)
        self._kick = threading.Event()  # hits answered: the animation thread ticks at once

    def open(self) -> None:
        """Bind the pose socket, connect to the input daemon (the base binds the control)."""
        cfg = self.config
        self._pub = socket(self.ctx, zmq.PUB)
        self.endpoints["pub"] = bind(self._pub, cfg.pub, "pub endpoint", cfg.security)
        self.rx.connect(self.ctx, cfg.sub, "sub endpoint", cfg.security)
        self.endpoints["sub"] = cfg.sub
        if cfg.osc_port is not None:
            self.osc = OscEndpoint(cfg.osc_port, SYNTH_ADDRESSES, "synth", log, cfg.osc_allow)
            host = "0.0.0.0" if cfg.osc_allow else "127.0.0.1"
            self.endpoints["osc"] = f"udp://{host}:{self.osc.port}"

    def hello(self) -> Hello:
        return Hello(
            self.name,
            "poses",
            self.config.performer,
            dict(self.endpoints),
            self.format,
            avatar=self.config.avatar,
        )

    def run(self, stop: threading.Event, on_ready: OnReady | None = None) -> int:
        """Serve until ``stop``; ``on_ready`` is called once the first poses are published
        (the synth is "ready" when it does its job, not when its sockets are bound). This
        thread answers hits; a second one animates (see the module docstring)."""
        halt = threading.Event()
        failed: list[BaseException] = []

        def animate() -> None:
            try:
                self._animate(stop, halt)
            except BaseException as exc:
                failed.append(exc)
                halt.set()

        worker = threading.Thread(target=animate, name="synth-animate", daemon=True)
        switch = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_S)
        worker.start()
        try:
            while not (stop.is_set() or halt.is_set()):
                if self.rx.poll(POLL_MS):
                    self._drain()  # every hit's contact goes out at once
                if self.osc is not None:
                    for cmd in self.osc.take():
                        with self._lock.answering():
                            self.command(cmd)
                if on_ready is not None and self.stats.pose_messages:
                    on_ready()
                    on_ready = None
        finally:
            halt.set()
            self._kick.set()
            worker.join()
            sys.setswitchinterval(switch)
            self.shutdown()
        if failed:
            raise failed[0]
        return 0

    def _animate(self, stop: threading.Event, halt: threading.Event) -> None:
        """The animation thread: a tick at ``tick_hz``, as soon as a note's limb is due to be
        committed, and at once when hits have been answered (their strokes follow with their
        provisional hands, ``SynthParams.provisional``)."""
        period = 1.0 / self.config.tick_hz
        next_tick = self.clock.now()
        last = next_tick - period
        provisional = self.synth.params.provisional
        while not (stop.is_set() or halt.is_set()):
            with self._lock:
                due = self.synth.next_due_s(last)
            wake = next_tick if due is None else min(next_tick, due)
            if not (provisional and self.stats.onsets != self._ticked):
                self._kick.wait(max(0.0, wake - self.clock.now()))
            self._kick.clear()  # before the count is read: a later kick is seen next time
            # the beat tracker's search (up to milliseconds) runs without the lock: it is this
            # thread's alone, the answer thread only lists what it heard
            with self._lock:
                heard = self.synth.window.take_heard()
            self.synth.window.track_heard(heard)
            with self._lock:
                now = self.clock.now()
                fresh = provisional and self.stats.onsets != self._ticked
                if fresh or now >= next_tick or (due is not None and now >= due):
                    self._ticked = self.stats.onsets
                    self.tick(now)
                    last = now
                    if now >= next_tick:
                        next_tick = max(next_tick + period, now)

    def command(self, cmd: Command) -> None:
        """One OSC command (see :mod:`services.show.osc`): a preset, a parameter or the state."""
        from livedrummer.body.expression import load_expression
        from livedrummer.errors import LivedrummerError

        osc = self.osc
        if osc is None:
            return
        now = self.clock.now()
        if cmd.address == STATE:
            osc.reply(cmd.sender, STATE, state_pairs(self.state(now)))
            return
        args = cmd.args
        try:
            if cmd.address == CUE:
                name = args[0] if len(args) == 1 else None
                cue = self.config.cues.get(name) if isinstance(name, str) else None
                if cue is None:
                    raise ValueError(f"no cue of that name (known: {', '.join(self.config.cues)})")
                self.synth.set_expression(cue.apply(self.synth.style.target), now)
                self.preset = cue.preset or self.preset
            elif cmd.address == PREFIX + "preset":
                if len(args) != 1 or not isinstance(args[0], str):
                    raise ValueError("expected one preset name")
                self.synth.set_expression(load_expression(args[0]), now)
                self.preset = args[0]
            else:
                name = cmd.address.removeprefix(PREFIX + "param/")
                if len(args) != 1 or isinstance(args[0], str | bool):
                    raise ValueError("expected one number")
                self.synth.set_param(name, float(args[0]), now)
            log.info("synth: %s %s", cmd.address, " ".join(str(a) for a in args))
        except (ValueError, LivedrummerError) as exc:
            osc.argument(cmd, str(exc))

    def state(self, now: float) -> dict[str, str | float | int]:
        """The synth's share of ``/livedrummer/state``: the preset, every expression
        parameter and the performer's state."""
        from livedrummer.body.expression import PARAMS, param_value

        expression = self.synth.style.target
        out: dict[str, str | float | int] = {"preset": self.preset}
        out.update({f"param/{p.name}": param_value(expression, p.name) for p in PARAMS})
        out["playing"] = int(now - self._last_onset_s < 2.0)
        out["onsets"] = self.stats.onsets
        out["performer"] = self.config.performer
        return out

    def _say(self, line: str | None) -> None:
        if line is not None:
            log.warning("synth: %s", line)

    def tick(self, now: float) -> None:
        """One tick of the animation thread, the lock held: bar cues, then the samples due
        (the lock let go while the curves are rebuilt and sampled: hits are answered then)."""
        self._fire_bar_cues(now)
        # between its steps (the lock let go) a re-animation waits while a hit is answered
        self._publish(self.synth.poses_until(now, answer=self._lock.wait_answered, lock=self._lock))
        self._say(self.late.poll(now))
        merged = self.synth.window.merged
        self._say(self.merged.add(merged - self._merged_seen, now))
        self._merged_seen = merged

    def _fire_bar_cues(self, now: float) -> None:
        """The cue list's ``bar`` cues whose bar the beat tracker has heard start: their style
        now, their camera and blackout to the displays at the bar's show time (STAGE_CUE)."""
        ahead = now + BAR_LEAD_S
        bars = self.synth.window.beat.bars(max(self._bars_from, now - 1.0), ahead)
        self._bars_from = ahead
        fired = self.bar_cues.due(bars)
        delay_s = self.synth.params.delay_s
        for start_s, cue in fired:
            if cue.styles:  # eased in from the bar's start on
                self.synth.set_expression(cue.apply(self.synth.style.target), start_s)
                self.preset = cue.preset or self.preset
            log.info(
                "synth: bar %d: cue %s (bar start %.3f s, show %.3f s)",
                cue.bar or 0,
                cue.name,
                start_s,
                start_s + delay_s,
            )
        rows = stage_cue_rows([(t + delay_s, cue.bar or 0, cue) for t, cue in fired])
        if rows.size:
            msg = Message(
                Kind.STAGE_CUE,
                rows,
                self.config.performer,
                self._seq,
                self.clock.now(),
                Stream.POSES,
            )
            self._pub.send_multipart(encode(msg), copy=False)
            self._seq += 1
            self.stats.stage_cues += rows.size

    def _publish(self, batch: PoseBatch) -> None:
        if batch.show_s.size == 0:
            return
        body = Pose(float(batch.show_s[0]), batch.rows)
        msg = Message(
            Kind.POSE, body, self.config.performer, self._seq, self.clock.now(), Stream.POSES
        )
        self._pub.send_multipart(encode(msg, self.format), copy=False)
        self._seq += 1
        self.stats.pose_messages += 1
        self.stats.pose_samples += batch.show_s.size

    def _forward(self, rows: np.ndarray, kind: Kind = Kind.SHOWN_ONSET) -> None:
        """Onsets (SHOWN_ONSET) or controls (SHOWN_CONTROL) as they arrive, on the pose
        stream, stamped with their show time (time + D), for displays that sound them or
        draw a score."""
        shown = rows.copy()
        shown["time_s"] += self.synth.params.delay_s
        msg = Message(kind, shown, self.config.performer, self._seq, self.clock.now(), Stream.POSES)
        self._pub.send_multipart(encode(msg), copy=False)
        self._seq += 1
        if kind is Kind.SHOWN_ONSET:
            self.stats.forwarded += shown.size
        else:
            self.stats.forwarded_controls += shown.size

    def _drain(self) -> None:
        """Everything waiting on the SUB socket, in batches of up to :data:`DRAIN_BATCH`
        messages: the onsets of a batch go to the synth together (their contacts are solved
        at once) and their quick contacts are published before the next batch is read, so a
        flood cannot hold them back. Each batch holds the synth's lock; the animation thread
        is kicked after each batch with onsets."""
        while True:
            read_at = self.clock.now()
            with self._lock.answering():
                got = self._drain_batch(read_at)
            if got < DRAIN_BATCH:
                return

    def _drain_batch(self, read_at: float) -> int:
        """One batch of :meth:`_drain` (the lock held; ``read_at``: the clock before the lock
        was taken, where the answer's time starts): how many messages it read."""
        onsets: list[np.ndarray] = []
        batch = self.rx.drain(DRAIN_BATCH)
        self.stats.missing += batch.missing
        self.stats.bad += batch.bad
        for msg in batch.messages:
            rows = self._receive(msg)
            if rows is not None:
                self._forward(rows)  # first: a display sounds them at onset + D
                onsets.append(rows)
        if onsets:
            rows = np.concatenate(onsets)
            self.synth.process(rows)
            self._publish(self.synth.take_quick())
            done = self.clock.now()
            self.stats.answer_s.append(done - read_at)
            # a contact published after its show time reaches every display too late
            shown = rows["time_s"].astype(np.float64) + self.synth.params.delay_s
            self._say(self.late.first(int(np.count_nonzero(shown < done)), done))
            self._kick.set()
        return batch.read

    def _receive(self, msg: Message) -> np.ndarray | None:
        """One message the receiver took from the input stream (checked, numbered: a gap or
        a restarted input daemon is counted and logged there): controls applied; its onset
        rows returned (None for anything else)."""
        if self.stats.first_seq is None:
            self.stats.first_seq = msg.seq
        self.stats.last_seq = msg.seq
        if msg.kind is Kind.ONSET and isinstance(msg.body, np.ndarray):
            rows = msg.body.copy()
            if self.config.input_offset_s:
                rows["time_s"] += self.config.input_offset_s
            if self.config.vary is not None:
                rows = vary_live(rows, self.config.vary)
            self.stats.onsets += rows.size
            self._last_onset_s = self.clock.now()
            return rows
        if msg.kind is Kind.CONTROL and isinstance(msg.body, np.ndarray):
            controls = msg.body
            if self.config.input_offset_s:
                controls = controls.copy()
                controls["time_s"] += self.config.input_offset_s
            self._forward(controls, Kind.SHOWN_CONTROL)  # in arrival order with the onsets
            for row in msg.body:
                self.synth.control(row)
            self.stats.controls += msg.body.size
        return None

    def release(self) -> None:
        if self.osc is not None:
            self.osc.stop()
            self.osc = None
        self.rx.close()
        if self._pub is not None:
            self._pub.close(0)
        self._pub = None

    def summary(self) -> dict[str, Any]:
        s = self.stats
        return {
            "onsets": s.onsets,
            "controls": s.controls,
            "forwarded_controls": s.forwarded_controls,
            "missing": s.missing,
            "bad": s.bad,
            "pose_messages": s.pose_messages,
            "pose_samples": s.pose_samples,
            "animations": self.synth.animations,
            "quick_contacts": self.synth.quick_contacts,
            "late_contacts": self.late.total,
            "merged_notes": self.merged.total,
            "stage_cues": s.stage_cues,
            "answer_ms": [
                round(float(np.percentile(s.answer_s, q)) * 1000, 2) if s.answer_s else None
                for q in (50, 99)
            ],
            "bad_messages": self.bad_messages(),
        }

    def bad_messages(self) -> dict[str, dict[str, int]]:
        """Dropped messages by socket ("events", "control") and kind; sockets with none left out."""
        out = {"events": self.bad_events.summary(), "control": self.bad_control.summary()}
        if self.osc is not None:
            out["osc"] = self.osc.bad.summary()
        return {k: v for k, v in out.items() if v}
