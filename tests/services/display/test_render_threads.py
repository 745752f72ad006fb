"""llvmpipe's thread count: the cores the process may run on, unless someone chose already."""

from __future__ import annotations

import os

import pytest

from services.display.context import use_cpu_cores


def test_llvmpipe_gets_the_cores_the_process_may_use(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("LP_NUM_THREADS", raising=False)
    assert use_cpu_cores() == len(os.sched_getaffinity(0))
    assert os.environ["LP_NUM_THREADS"] == str(len(os.sched_getaffinity(0)))


def test_a_thread_count_set_already_is_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LP_NUM_THREADS", "1")  # a worker process given one core
    assert use_cpu_cores() == 1
    assert os.environ["LP_NUM_THREADS"] == "1"
