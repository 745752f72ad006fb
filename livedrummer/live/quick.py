"""Quick contacts: every arriving hit's contact pose, sent within a millisecond.

The synthesizer's curves are rebuilt (10-20 ms) whenever its window of notes changes. A hit
need not wait for that to be shown striking: its contact pose is the current pose at the
onset with one limb moved onto the struck piece, and that is one inverse-kinematics solve.
:func:`quick_contact` takes a :class:`QuickState` (what
:meth:`~livedrummer.live.synth.LiveSynth.quick_state` copies out of the synthesizer: from its
sample ledger the samples it published lately and holds ahead and the quick contacts it sent
that the curves do not have yet; from its curve set a view of the curves, for a time no
sample is near) and the onsets that just arrived with the limbs the synthesizer gives them
(decided, or provisional), and returns one pose record per onset time, to show at onset + D:

* the body as sampled nearest the onset (torso, head, the other limbs), or the quick contact
  already sent for that time (a chord whose notes came in two messages); the curves are
  sampled only when no sample exists yet (start-up): one sample of the curves costs several
  milliseconds (10 with a cross-fade under way), more than the whole answer otherwise, so a
  hit that finds the animation behind (a busy machine) starts from the newest sample there
  is, however old; its limb still lands exactly on its target, the rest of the body is as
  of that sample until the strokes replace it;
* each striking limb put on its piece by :func:`~livedrummer.body.strike.strike_poses` (the
  body package's one strike solve, shared with the animation's contact keys): an arm from
  that sample's own shoulder and chest, so the stick tip lies on the target exactly; a foot
  on its footboard, looked up (:func:`~livedrummer.body.strike.foot_contacts`: a foot's
  contact depends on the piece alone, so the synth solves it once at start); the struck
  piece's channels as at a hit.

The whole batch is solved at once (one IK call per limb), so a burst of notes that arrived
together costs what one does. Nothing in the state is changed. The re-animated curves
replace these samples a moment later with the whole stroke (the same contact when the
provisional limb was right: both are the same IK onto the same point)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.body.rig import Rig
from livedrummer.body.strike import FootContacts, strike_poses
from livedrummer.live.curves import CurveView, sample_curves


@dataclass(frozen=True)
class QuickState:
    """A read-only copy of what :func:`quick_contact` needs (see the module docstring)."""

    rig: Rig
    dtype: np.dtype
    curves: CurveView
    samples_t: np.ndarray  # performance times of samples published lately and held ahead
    samples: np.ndarray  # their pose records
    struck: dict[float, np.ndarray]  # quick contacts not yet in the curves, by onset time
    feet: FootContacts | None = None  # the feet's contacts, solved once (else solved here)


def quick_contact(
    state: QuickState,
    rows: np.ndarray | np.void,
    limbs: np.ndarray | int,
    pieces: np.ndarray | int,
) -> tuple[np.ndarray, np.ndarray]:
    """Onset times and pose records to send at once (shown at onset + D) for onsets ``rows``
    (ONSET_DTYPE), played by ``limbs`` (0-3: right hand, left hand, right foot, left foot;
    -1: not played) on kit pieces ``pieces``: one record per distinct onset time, ascending
    (the limbs of a chord strike together in it); empty when there is nothing to start from
    yet (see the module docstring). One IK solve per limb for the whole batch: a burst costs
    what a hit does."""
    rows = np.atleast_1d(np.asarray(rows))
    limbs, pieces = np.atleast_1d(limbs), np.atleast_1d(pieces)
    play = (limbs >= 0) & (pieces >= 0)
    if not play.any():
        return np.zeros(0), np.zeros(0, state.dtype)
    times, at = np.unique(rows["time_s"][play].astype(np.float64), return_inverse=True)
    base = _bodies_at(state, times)
    if base is None:
        return np.zeros(0), np.zeros(0, state.dtype)
    hits, limb, piece = rows[play], limbs[play], pieces[play]
    for code in range(4):
        sel = np.flatnonzero(limb == code)
        # a limb given two notes at one time: the last one is drawn
        _, last = np.unique(at[sel][::-1], return_index=True)
        sel = sel[::-1][last]
        if sel.size:
            h = hits[sel]
            base[at[sel]] = strike_poses(
                state.rig,
                base[at[sel]],
                code,
                piece[sel].astype(np.int64),
                h["zone"].astype(np.int64),
                h["velocity"],
                h["openness"],
                state.feet,
            )
    return times, base


def _bodies_at(state: QuickState, times: np.ndarray) -> np.ndarray | None:
    """The body at each of ``times``: the quick contact already sent for that time (a chord
    completed), else the published or held sample nearest it, however far, else (nothing
    sampled yet) sampled from the curves."""
    out = np.zeros(times.size, state.dtype)
    todo = np.ones(times.size, dtype=bool)
    for k, t in enumerate(times.tolist()):
        if t in state.struck:
            out[k], todo[k] = state.struck[t], False
    if todo.any() and state.samples_t.size:
        i = np.clip(np.searchsorted(state.samples_t, times), 1, state.samples_t.size - 1)
        i = (
            np.where(
                np.abs(state.samples_t[i - 1] - times) < np.abs(state.samples_t[i] - times),
                i - 1,
                i,
            )
            if state.samples_t.size > 1
            else np.zeros_like(i)
        )
        out[todo] = state.samples[i[todo]]
        todo[:] = False
    if todo.any():
        if state.curves.curves is None:
            return None
        out[todo], _ = sample_curves(state.curves, times[todo])
    return out
