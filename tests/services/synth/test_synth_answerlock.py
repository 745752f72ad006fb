"""The synth service's lock lets the answer thread go first."""

from __future__ import annotations

import threading
import time

from services.synth.answerlock import AnswerFirstLock


def test_an_answer_waiting_for_the_lock_goes_before_the_animation_takes_it_back() -> None:
    lock = AnswerFirstLock()
    order: list[str] = []
    lock.acquire()  # the animation thread in a step

    def answer() -> None:
        with lock.answering():
            order.append("answer")

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    deadline = time.monotonic() + 5.0
    while not lock.wanted and time.monotonic() < deadline:
        time.sleep(0.001)
    assert lock.wanted and not order, "the answer waits for the step"
    lock.release()
    with lock:  # the animation thread takes the lock back at once: after the answer
        order.append("animation")
    thread.join(5.0)
    assert order == ["answer", "animation"]
    assert not lock.wanted
    lock.wait_answered()  # returns at once with no answer under way


def test_between_its_steps_the_animation_waits_while_a_hit_is_answered() -> None:
    lock = AnswerFirstLock()
    inside, leave = threading.Event(), threading.Event()

    def answer() -> None:
        with lock.answering():
            inside.set()
            leave.wait(5.0)

    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    assert inside.wait(5.0)
    waited = threading.Event()

    def step() -> None:
        lock.wait_answered()
        waited.set()

    stepper = threading.Thread(target=step, daemon=True)
    stepper.start()
    assert not waited.wait(0.05), "the step went on during the answer"
    leave.set()
    assert waited.wait(5.0)
    thread.join(5.0)
    stepper.join(5.0)
