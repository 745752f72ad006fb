"""The one sequence policy and the intake, fed frames by hand (no sockets).

A stream with a gap, a duplicate, a reorder, a sender restart seen at 0, one seen late (a
small number with a fresh send time), one so far back that it can only be a restart, and
junk: the counts and the messages taken are the policy's (livedrummer.protocol.sequence).
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from livedrummer import protocol as p
from livedrummer.protocol.sequence import REORDER_WINDOW
from services.wire.stream_rx import LOG_EVERY_S, Counts, StreamReceiver

Frames = list[bytes]
KINDS = (p.Kind.ONSET, p.Kind.HEARTBEAT)


def beat(seq: int, send_s: float, performer: int = 2) -> Frames:
    return p.encode(p.Message(p.Kind.HEARTBEAT, None, performer, seq, send_s))


def onset(seq: int, send_s: float) -> Frames:
    rows = np.zeros(1, p.SPECS[p.Kind.ONSET].rows)
    rows["note"], rows["velocity"], rows["openness"], rows["instrument"] = 38, 90, np.nan, 1
    return p.encode(p.Message(p.Kind.ONSET, rows, 2, seq, send_s))


def junk() -> list[tuple[str, Frames]]:
    good = beat(0, 0.0)
    return [
        ("header", [p.MAGIC + b"\x00" * 7]),  # a truncated header
        ("version", [good[0][:4] + bytes([p.PROTOCOL_VERSION + 1]) + good[0][5:], *good[1:]]),
        ("frames", [good[0]]),  # its payload frame missing
        ("unexpected", p.encode(p.Message(p.Kind.HELLO, p.Hello("x", "y"), 2, 4, 99.0))),
    ]


def test_the_policy_on_one_stream() -> None:
    intake = p.StreamIntake(KINDS)
    S = p.SeqStatus  # noqa: N806
    script: list[tuple[Frames, p.SeqStatus | str]] = [
        (beat(7, 1.0), S.FIRST),  # joined mid-stream: nothing counted
        (beat(8, 1.1), S.OK),
        (onset(11, 1.2), S.GAP),  # 9, 10 lost
        (beat(10, 1.15), "duplicate"),  # late, after its gap: dropped, stays missing
        (beat(11, 1.2), "duplicate"),  # the same again
        (beat(12, 1.3), S.OK),
        (beat(0, 5.0), S.RESTART),  # the sender started again
        (beat(1, 5.1), S.OK),
        (beat(2, 5.2), S.OK),
        (beat(3, 5.3), S.OK),
        (beat(1, 9.0), S.RESTART),  # restarted again, its 0 missed: a fresh send time
        (beat(2, 9.1), S.OK),
        (beat(1, 9.05), "duplicate"),  # back and older: a reorder
    ]
    for frames, want in script:
        got = intake.take(frames)
        if isinstance(want, str):
            assert isinstance(got, p.Dropped) and got.kind == want, (want, got)
        else:
            assert isinstance(got, p.Taken) and got.seq.status is want, (want, got)
    stats = intake.tracker.stats[(2, 0)]
    assert (stats.received, stats.missing, stats.duplicates, stats.restarts) == (10, 2, 3, 2)
    assert not intake.bad


def test_a_number_further_back_than_any_reorder_is_a_restart_whatever_its_time() -> None:
    t = p.SequenceTracker()
    t.observe(0, 0, 500, 10.0)
    back = 501 - REORDER_WINDOW  # the deepest reorder: older time, so a duplicate
    assert t.observe(0, 0, back, 9.0).status is p.SeqStatus.DUPLICATE
    far = t.observe(0, 0, back - 1, 3.0)  # one further, and a clock that went back too
    assert far.status is p.SeqStatus.RESTART
    assert t.observe(0, 0, back - 3, 2.0).status is p.SeqStatus.DUPLICATE  # behind the new run


def test_junk_is_counted_by_kind_and_never_read_as_loss_or_restart() -> None:
    intake = p.StreamIntake(KINDS, performer=2)
    assert isinstance(intake.take(beat(0, 1.0)), p.Taken)
    cases = junk()
    for kind, frames in cases:
        got = intake.take(frames)
        assert isinstance(got, p.Dropped) and got.kind == kind, (kind, got)
    other = intake.take(beat(1, 1.1, performer=5))  # another performer's number: not ours
    assert isinstance(other, p.Dropped) and other.kind == "unexpected"
    assert isinstance(intake.take(beat(1, 1.1)), p.Taken)  # so 1 follows 0: no gap
    assert intake.bad == {"header": 1, "version": 1, "frames": 1, "unexpected": 2}
    seq = intake.seq
    assert (seq.received, seq.missing, seq.duplicates, seq.restarts) == (2, 0, 0, 0)


def test_unsequenced_intake_takes_every_good_message() -> None:
    intake = p.StreamIntake(KINDS, sequenced=False)
    got = [intake.take(beat(s, 1.0)) for s in (4, 2, 2, 9)]
    assert all(isinstance(g, p.Taken) and g.seq.status is p.SeqStatus.OK for g in got)


def test_the_receiver_logs_loss_at_most_once_per_period(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING)
    now = [0.0]
    rx = StreamReceiver("unit stream", logging.getLogger("test.rx"), KINDS, clock=lambda: now[0])
    for frames in (beat(0, 1.0), beat(3, 1.1), beat(6, 1.2), beat(7, 1.3), beat(0, 2.0)):
        rx.take(frames)  # a gap logged at once; a gap and a restart within the period: held
    for _, frames in junk() * 3:
        rx.take(frames)  # each kind logged once
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0] == "unit stream: 2 messages lost, up to #3", lines
    assert sum("dropped a bad message" in line for line in lines) == 4, lines
    assert not any("restarted" in line for line in lines)
    now[0] = LOG_EVERY_S
    rx.take(beat(2, 2.1))  # the next gap, a period later: one line with what was held
    assert caplog.records[-1].getMessage() == (
        "unit stream: 3 messages lost in 2 gaps; the sender restarted (its numbers began "
        "again), up to #2"
    )
    assert rx.counts == Counts(received=6, missing=5, duplicates=0, restarts=1, bad=12)
    assert rx.bad.summary() == {"frames": 3, "header": 3, "unexpected": 3, "version": 3}
    assert rx.bad.summary() == dict(rx.intake.bad)
    rx.close()  # nothing held: no loss line, one bad-message total
    assert "dropped bad messages" in caplog.records[-1].getMessage()
