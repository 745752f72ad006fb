"""Saying when the show is behind: counts of late things, and a warning at most every 10 s.

A late avatar is worse than a slow one when nobody says so: on a loaded machine the synth
can answer hits after the visual delay D, so their contacts reach the display after the
frame that should have shown them, and a headless recording can repeat frames for seconds.
:class:`BehindCounter` counts such events (late contacts in the synth, late pose samples
and repeated frames in the display) in total and in the current window, and hands back one
warning line when a window with any of them closes, so a service logs at most one line every
``window_s`` however bad it gets, and its summary carries the totals. The synth also counts,
in a one-second window, the notes the sticking merged into another stroke (a flam or double
stroke of the nearer hand: three hand notes within the chord window).

Pure logic on an injected time (the caller's clock); nothing here logs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

WINDOW_S = 10.0


@dataclass
class BehindCounter:
    """Late events of one kind (``what``, plural noun phrase) with a rate-limited warning."""

    what: str
    advice: str = ""
    window_s: float = WINDOW_S
    total: int = 0
    _window: int = field(default=0, repr=False)
    _opened_s: float | None = field(default=None, repr=False)

    def add(self, n: int, now_s: float) -> str | None:
        """Count ``n`` late events at ``now_s``; the warning line when a window closes."""
        if n <= 0:
            return self.poll(now_s)
        self.total += n
        self._window += n
        if self._opened_s is None:
            self._opened_s = now_s
        return self.poll(now_s)

    def poll(self, now_s: float) -> str | None:
        """The warning for the window just closed, if it counted anything (else None)."""
        if self._opened_s is None or now_s - self._opened_s < self.window_s:
            return None
        n, self._window, self._opened_s = self._window, 0, None
        tail = f"; {self.advice}" if self.advice else ""
        return f"{n} {self.what} in the last {self.window_s:g} s ({self.total} so far){tail}"

    def first(self, n: int, now_s: float) -> str | None:
        """As :meth:`add`, but also warns at once for the very first late event of a show."""
        first = self.total == 0 and n > 0
        line = self.add(n, now_s)
        if first and line is None:
            tail = f"; {self.advice}" if self.advice else ""
            return f"{n} {self.what} (the first; counted from now on){tail}"
        return line
