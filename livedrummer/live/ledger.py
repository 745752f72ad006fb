"""The live synth's sample ledger: the one store of pose samples, published, held or quick.

Why this shape. A live synth has pose samples in three states, and each used to have its own
store, with its own clean-up rule, inside the synth: samples *published* lately (the body a
quick contact starts from), samples *held* ahead of what was published (sampled a chunk at a
time from the current curves, handed out as the clock reaches them), and *quick contacts*
(a hit's contact pose sent on arrival, before the curves know the hit). Every batch the
synth sends is cut from here, so the rules that keep the display's track whole live in one
place:

* a batch replaces the range it covers on the display (:class:`~livedrummer.live.track.PoseTrack`),
  so a batch carries every quick contact in its range that the curves it came from lack
  (:meth:`SampleLedger.with_struck`), and a quick batch fills the range from the end of what
  was published to its last contact with the samples published or held there;
* held samples are replaced as a whole, only when their successors are complete
  (:meth:`SampleLedger.hold`), so a quick contact answered while the curves are being
  rebuilt still starts from a sample that exists;
* what was published is kept for ``keep_s`` (a quarter second) of performance time, and a
  quick contact is forgotten once the curves have it or it is that old.

All times here are performance times (show time minus D); the ledger never samples curves
itself. Limits: the memory held is bounded by ``keep_s`` plus one chunk of samples at the
synth's rate and the quick contacts of the last ``keep_s`` (twice that while nothing is
published), however long the show; a quick contact more than ``keep_s`` behind the committed
horizon is dropped even if the curves never took it (a hit the curves left out is then only
shown by its own batch).
"""

from __future__ import annotations

import math

import numpy as np

#: published samples kept as the body quick contacts start from (performance seconds)
KEEP_S = 0.25


class SampleLedger:
    """Published, held and quick samples of one synth (see the module docstring)."""

    def __init__(self, dtype: np.dtype, keep_s: float = KEEP_S) -> None:
        self.dtype = dtype
        self.keep_s = keep_s
        self.reset()

    def reset(self) -> None:
        #: the last performance time published from the curves (None before the first batch)
        self.published_s: float | None = None
        self._quick_end = -math.inf  # the last onset time a quick batch reached
        self._quick_lo = math.inf  # range of quick contacts added since the last take
        self._quick_hi = -math.inf
        self._struck: dict[float, np.ndarray] = {}  # quick contacts the curves do not have yet
        self._held_t = np.zeros(0)  # samples of the current curves ahead of what was published
        self._held_rows = np.zeros(0, self.dtype)
        self._sent_t = np.zeros(0)  # samples published lately (the body a quick contact uses)
        self._sent_rows = np.zeros(0, self.dtype)

    def _empty(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(0), np.zeros(0, self.dtype)

    # -- what quick contacts read --------------------------------------------------------------

    def samples(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples published lately and held ahead, by time (after a rebuild the held
        ones may start before the end of the published ones)."""
        t = np.concatenate([self._sent_t, self._held_t])
        order = np.argsort(t, kind="stable")
        return t[order], np.concatenate([self._sent_rows, self._held_rows])[order]

    def struck(self) -> dict[float, np.ndarray]:
        """A copy of the quick contacts the curves do not have yet, by onset time."""
        return dict(self._struck)

    # -- held samples --------------------------------------------------------------------------

    def held_until(self) -> float | None:
        """The last held time, or None when nothing is held."""
        return float(self._held_t[-1]) if self._held_t.size else None

    def hold(self, times: np.ndarray, rows: np.ndarray, *, replace: bool) -> None:
        """Samples ahead of what was published, ascending: instead of the held ones
        (``replace``: the curves were rebuilt) or after them."""
        if replace:
            self._held_t, self._held_rows = times, rows
        else:
            self._held_t = np.concatenate([self._held_t, times])
            self._held_rows = np.concatenate([self._held_rows, rows])

    def drop_held(self) -> None:
        self._held_t, self._held_rows = self._empty()

    # -- publishing ----------------------------------------------------------------------------

    def publish(
        self, start: float, top: float, committed_s: float, contacts_s: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The held samples in ``(start, top]`` (with the quick contacts the curves lack,
        see :meth:`with_struck`), now published; later ones stay held. ``committed_s``: the
        committed horizon; ``contacts_s``: the contacts the current curves have (their quick
        contacts are forgotten)."""
        take = (self._held_t > start) & (self._held_t <= top)
        times, rows = self._held_t[take], self._held_rows[take]
        later = self._held_t > top
        self._held_t, self._held_rows = self._held_t[later], self._held_rows[later]
        self.published_s = max(top, start)
        if times.size:
            older = self._sent_t < times[0]  # a re-sent range replaces what was sent there
            t_all = np.concatenate([self._sent_t[older], times])
            recent = t_all > t_all[-1] - self.keep_s
            self._sent_t = t_all[recent]
            self._sent_rows = np.concatenate([self._sent_rows[older], rows])[recent]
        self._struck = {
            t: r
            for t, r in self._struck.items()
            if t > committed_s - self.keep_s and not np.any(contacts_s == t)
        }
        return self.with_struck(times, rows, start, top)

    # -- quick contacts ------------------------------------------------------------------------

    def add_quick(self, times: np.ndarray, rows: np.ndarray) -> None:
        """Quick contacts (onset times, pose records) to go out with :meth:`take_quick`; for a
        time given twice (a chord completed) the last one wins."""
        if times.size == 0:
            return
        newest = float(times.max())
        if self._struck and min(self._struck) < newest - 2 * self.keep_s:
            # also while nothing is published (a re-animation answering a flood)
            self._struck = {t: r for t, r in self._struck.items() if t >= newest - 2 * self.keep_s}
        self._struck.update(zip(times.tolist(), rows, strict=True))
        self._quick_lo = min(self._quick_lo, float(times.min()))
        self._quick_hi = max(self._quick_hi, newest)

    def take_quick(self) -> tuple[np.ndarray, np.ndarray]:
        """The quick contacts added since the last call as one ascending range: from the end
        of what was published (grid samples, or the last quick batch) or the first contact,
        to the last contact, the samples between filled in from what was published and is
        held (a batch replaces its range: contacts alone would hide those), with every quick
        contact in the range, this call's and earlier ones (leaving one out would erase it)."""
        if self._quick_hi == -math.inf:
            return self._empty()
        lo, hi = self._quick_lo, self._quick_hi
        self._quick_lo, self._quick_hi = math.inf, -math.inf
        sent_end = max(
            self.published_s if self.published_s is not None else -math.inf, self._quick_end
        )
        lo = min(lo, sent_end)
        self._quick_end = max(self._quick_end, hi)
        held_t, held = self.samples()
        fill = (held_t > lo) & (held_t <= hi)
        return self.with_struck(held_t[fill], held[fill], np.nextafter(lo, -math.inf), hi)

    def with_struck(
        self, times: np.ndarray, rows: np.ndarray, start: float, top: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """``times``/``rows`` with every quick contact in ``(start, top]`` put in (in place of a
        sample at its time): a batch from curves that lack a hit (it arrived while they were
        being built) still carries that hit's contact."""
        add = [t for t in self._struck if start < t <= top]
        if not add:
            return times, rows
        keep = ~np.isin(times, add)
        t_all = np.concatenate([times[keep], np.array(add)])
        r_all = np.concatenate([rows[keep], np.array([self._struck[t] for t in add], self.dtype)])
        order = np.argsort(t_all, kind="stable")
        return t_all[order], r_all[order]
