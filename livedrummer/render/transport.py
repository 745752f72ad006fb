"""SMED's transport for file playback in a window: play/pause, seek, step, reverse, speed, marks.

A small state machine with an injected clock: the window calls :meth:`Transport.advance` with
the wall (or audio) time that passed, and :meth:`Transport.apply` with an action name from
:data:`KEYS`; nothing here reads a clock or a keyboard, so tests step it by hand. Position is
clamped to ``[0, duration_s]``; playing into either end pauses there. Speed moves along
:data:`SPEEDS` (slow motion for study, fast for scrubbing); reverse plays backwards at the same
speed. Step moves one ``step_s`` (a video frame by default) and pauses, as a step key should.
Markers (SMED's song flags) are sorted positions; next/previous jump between them.

Loop A-B (SMED's "repeat a passage", the practice tools' loop): ``loop_start`` and ``loop_end``
set the two ends at the position (either first; if B comes before A they swap), and playing
through one end wraps to the other, forwards B to A, in reverse A to B, carrying the
overshoot so the playback clock never stutters; ``loop_clear`` plays the whole file again.
The step size is one of :data:`STEPS` (a video frame by default, then 10, 50, 100 and
500 ms), cycled by ``step_size`` or set by the caller.
"""

from __future__ import annotations

import bisect
from collections.abc import Callable
from dataclasses import dataclass, field

SPEEDS: tuple[float, ...] = (0.125, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 4.0)
SEEK_S = 5.0
#: step sizes cycled by the step-size key: a 30 fps frame, then 10, 50, 100 and 500 ms
STEPS: tuple[float, ...] = (1.0 / 30.0, 0.010, 0.050, 0.100, 0.500)
MIN_LOOP_S = 0.05  # a loop shorter than this is not set (A and B on the same spot)

#: key name (as the window reports it) -> transport action
KEYS: dict[str, str] = {
    "space": "play_pause",
    "right": "step_forward",
    "left": "step_back",
    "shift+right": "seek_forward",
    "shift+left": "seek_back",
    "home": "to_start",
    "end": "to_end",
    "r": "reverse",
    "equal": "faster",
    "kp_add": "faster",
    "minus": "slower",
    "kp_subtract": "slower",
    "0": "normal_speed",
    "m": "mark",
    "right_bracket": "next_mark",
    "left_bracket": "previous_mark",
    "a": "loop_start",
    "b": "loop_end",
    "l": "loop_clear",
    "s": "step_size",
}


@dataclass
class Transport:
    """Playback position and mode of one performance (see the module docstring)."""

    duration_s: float
    step_s: float = 1.0 / 30.0
    position_s: float = 0.0
    playing: bool = False
    reverse: bool = False
    speed_index: int = SPEEDS.index(1.0)
    markers: list[float] = field(default_factory=list)
    loop: tuple[float, float] | None = None  # (A, B) seconds, A < B
    _loop_ends: tuple[float | None, float | None] = (None, None)  # set so far, no loop yet

    @property
    def speed(self) -> float:
        return SPEEDS[self.speed_index]

    def advance(self, dt_s: float) -> float:
        """Move by ``dt_s`` seconds of clock time if playing; return the new position."""
        if self.playing and dt_s > 0:
            direction = -1.0 if self.reverse else 1.0
            target = self.position_s + direction * dt_s * self.speed
            if self.loop is not None:
                a, b = self.loop
                inside = a - 1e-9 <= self.position_s <= b + 1e-9
                if inside and not self.reverse and target > b:
                    target = a + (target - b) % (b - a)
                elif inside and self.reverse and target < a:
                    target = b - (a - target) % (b - a)
            self._move_to(target)
            at_end = self.position_s <= 0.0 if self.reverse else self.position_s >= self.duration_s
            if at_end:
                self.playing = False
        return self.position_s

    def _move_to(self, t_s: float) -> None:
        self.position_s = min(max(t_s, 0.0), self.duration_s)

    def seek(self, t_s: float) -> None:
        self._move_to(t_s)

    def apply(self, action: str) -> None:
        """Do one :data:`KEYS` action by name; unknown names raise ``KeyError``."""
        handlers: dict[str, Callable[[], None]] = {
            "play_pause": self._play_pause,
            "step_forward": lambda: self._step(+1),
            "step_back": lambda: self._step(-1),
            "seek_forward": lambda: self._move_to(self.position_s + SEEK_S),
            "seek_back": lambda: self._move_to(self.position_s - SEEK_S),
            "to_start": lambda: self._move_to(0.0),
            "to_end": lambda: self._move_to(self.duration_s),
            "reverse": self._toggle_reverse,
            "faster": lambda: self._speed(+1),
            "slower": lambda: self._speed(-1),
            "normal_speed": self._normal_speed,
            "mark": self._mark,
            "next_mark": lambda: self._jump(+1),
            "previous_mark": lambda: self._jump(-1),
            "loop_start": lambda: self._set_loop_end(0),
            "loop_end": lambda: self._set_loop_end(1),
            "loop_clear": self._loop_clear,
            "step_size": self._next_step,
        }
        handlers[action]()

    def _play_pause(self) -> None:
        if not self.playing:
            # Playing from the end forwards (or the start backwards) starts over.
            if not self.reverse and self.position_s >= self.duration_s:
                self.position_s = 0.0
            elif self.reverse and self.position_s <= 0.0:
                self.position_s = self.duration_s
        self.playing = not self.playing

    def _step(self, n: int) -> None:
        self.playing = False
        self._move_to(self.position_s + n * self.step_s)

    def _toggle_reverse(self) -> None:
        self.reverse = not self.reverse

    def _speed(self, delta: int) -> None:
        self.speed_index = min(max(self.speed_index + delta, 0), len(SPEEDS) - 1)

    def _normal_speed(self) -> None:
        self.speed_index = SPEEDS.index(1.0)

    def _mark(self) -> None:
        if self.position_s not in self.markers:
            bisect.insort(self.markers, self.position_s)

    def _jump(self, direction: int) -> None:
        eps = 1e-9
        if direction > 0:
            k = bisect.bisect_right(self.markers, self.position_s + eps)
            if k < len(self.markers):
                self._move_to(self.markers[k])
        else:
            k = bisect.bisect_left(self.markers, self.position_s - eps)
            if k > 0:
                self._move_to(self.markers[k - 1])

    def _set_loop_end(self, end: int) -> None:
        """End ``end`` (0: A, 1: B) of the loop at the position; once both ends are known and
        apart, the loop is set (the earlier of the two is A)."""
        ends = list(self.loop) if self.loop is not None else list(self._loop_ends)
        ends[end] = self.position_s
        a, b = ends
        if a is not None and b is not None and abs(b - a) >= MIN_LOOP_S:
            self.loop = (min(a, b), max(a, b))
            self._loop_ends = (None, None)
        else:
            self.loop = None
            self._loop_ends = (a, b)

    def _loop_clear(self) -> None:
        self.loop = None
        self._loop_ends = (None, None)

    def _next_step(self) -> None:
        here = min(range(len(STEPS)), key=lambda i: abs(STEPS[i] - self.step_s))
        self.step_s = STEPS[(here + 1) % len(STEPS)]
