"""The synth's curves in a worker process (services.synth.curveworker): a real child process.

The synth fed through a worker publishes exactly what the in-process synth does; a killed or
stopped child is replaced and the samples stay those of the same curves; a bad request is
answered with an error and the child carries on.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator

import numpy as np
import pytest

from livedrummer.body.rig import Rig
from livedrummer.live.curves import CurveSet
from livedrummer.live.synth import LiveSynth, PoseBatch, SynthParams
from livedrummer.timeline.performance import Performance
from services.synth.curveworker import CurveWorker, CurveWorkerError, dumps

START = 5000.0
TICK_S = 1 / 120


@pytest.fixture
def worker(rig: Rig) -> Iterator[CurveWorker]:
    with CurveWorker(rig, SynthParams().blend_s, timeout_s=5.0) as w:
        yield w


def first_seconds(groove: Performance, seconds: float) -> np.ndarray:
    """The groove's first ``seconds`` of onsets, moved to start at :data:`START`."""
    t = groove.onsets["time_s"]
    onsets: np.ndarray = groove.onsets[t < t[0] + seconds].copy()
    onsets["time_s"] += START - t[0]
    return onsets


def play(synth: LiveSynth, onsets: np.ndarray) -> list[PoseBatch]:
    """``onsets`` into ``synth`` on a stepped clock (ticks between them, as the service's)."""
    out: list[PoseBatch] = []
    now = float(onsets["time_s"][0]) - 0.2
    out.append(synth.poses_until(now))
    for row in onsets:
        while now + TICK_S < float(row["time_s"]):
            now += TICK_S
            out.append(synth.poses_until(now))
        synth.process(row)
        out.append(synth.take_quick())
        out.append(synth.poses_until(float(row["time_s"])))
    for _ in range(30):
        now += TICK_S
        out.append(synth.poses_until(now))
    return out


def rebuild_args(rig: Rig, groove: Performance) -> dict[str, object]:
    """The arguments of one re-animation of the synth, caught from an in-process synth."""
    synth = LiveSynth(rig, SynthParams())
    caught: list[dict[str, object]] = []
    rebuild = synth.curves.rebuild

    def spy(*args: object, **kwargs: object) -> object:
        names = (
            "sticking",
            "beats",
            "openness",
            "key",
            "contacts_s",
            "chokes",
            "start_s",
            "horizon_s",
            "answer",
            "expression",
            "change",
        )
        caught.append({**dict(zip(names, args, strict=False)), **kwargs})
        return rebuild(*args, **kwargs)  # type: ignore[arg-type]

    synth.curves.rebuild = spy  # type: ignore[method-assign]
    onsets = first_seconds(groove, 1.5)
    play(synth, onsets)
    args = caught[-1]
    args.pop("answer", None)
    return args


def test_the_synth_through_a_worker_publishes_what_it_does_in_process(
    rig: Rig, groove: Performance, worker: CurveWorker
) -> None:
    onsets = first_seconds(groove, 2.0)
    here = play(LiveSynth(rig, SynthParams()), onsets)
    there = play(LiveSynth(rig, SynthParams(), curves=worker), onsets)
    assert len(here) == len(there)
    samples = 0
    for a, b in zip(here, there, strict=True):
        np.testing.assert_array_equal(a.show_s, b.show_s)
        assert a.rows.tobytes() == b.rows.tobytes()
        samples += a.show_s.size
    assert samples > 400, "the run published the strokes"
    assert worker.animations > 5 and worker.restarts == 0


@pytest.mark.parametrize("how", ["killed", "stopped"])
def test_a_dead_or_hung_worker_is_replaced_with_the_same_curves(
    rig: Rig, groove: Performance, how: str
) -> None:
    args = rebuild_args(rig, groove)
    times = np.linspace(float(args["start_s"]), float(args["horizon_s"]) + 0.05, 40)  # type: ignore[arg-type]
    local = CurveSet(rig, SynthParams().blend_s)
    local.rebuild(**args)  # type: ignore[arg-type]
    expected = local.sample(times)
    with CurveWorker(rig, SynthParams().blend_s, timeout_s=1.0) as worker:
        worker.rebuild(**args)  # type: ignore[arg-type]
        first = worker.pid
        assert first is not None
        os.kill(first, signal.SIGKILL if how == "killed" else signal.SIGSTOP)
        rows = worker.sample(times)  # the stopped one killed; the rebuild sent to the new one
        assert worker.restarts == 1 and worker.pid not in (None, first)
        assert rows.tobytes() == expected.tobytes()
        assert worker.sample(times).tobytes() == expected.tobytes()


def test_a_bad_request_is_answered_with_an_error_and_the_worker_carries_on(
    rig: Rig, groove: Performance, worker: CurveWorker
) -> None:
    pid = worker.pid
    assert worker._exchange(b"not a pickle") == ("error", "UnpicklingError: invalid load key, 'n'.")
    reply = worker._exchange(dumps(("frobnicate", 1)))
    assert reply == ("error", "ValueError: unknown request 'frobnicate' (of 2 items)")
    args = rebuild_args(rig, groove)
    with pytest.raises(CurveWorkerError, match="curve worker: "):
        worker.rebuild(**{**args, "sticking": None})  # type: ignore[arg-type]
    worker.rebuild(**args)  # type: ignore[arg-type]
    rows = worker.sample(np.array([float(args["horizon_s"])]))  # type: ignore[arg-type]
    assert rows.size == 1 and np.isfinite(rows["position"]).all()
    assert worker.pid == pid and worker.restarts == 0
