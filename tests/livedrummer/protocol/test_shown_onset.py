"""SHOWN_ONSET: onsets a synth forwards to its displays, stamped with their show time."""

from __future__ import annotations

import numpy as np
import pytest

from livedrummer import protocol as p
from livedrummer.errors import ProtocolError
from livedrummer.timeline.events import ONSET_DTYPE


def rows() -> np.ndarray:
    r = np.zeros(2, ONSET_DTYPE)
    r["time_s"] = [10.03, 10.28]
    r["note"], r["velocity"], r["channel"] = [36, 38], [90, 120], 9
    r["instrument"], r["openness"] = [1, 2], np.nan
    return r


def test_a_shown_onset_round_trips_on_the_pose_stream() -> None:
    msg = p.Message(
        p.Kind.SHOWN_ONSET, rows(), performer=3, seq=7, send_time_s=10.0, stream=p.Stream.POSES
    )
    frames = p.encode(msg)
    assert frames[0][:6] == p.topic(p.Kind.SHOWN_ONSET) and p.PROTOCOL_VERSION == 2
    back = p.decode(frames)
    assert back.kind is p.Kind.SHOWN_ONSET and back.stream == p.Stream.POSES
    assert (back.performer, back.seq, back.send_time_s) == (3, 7, 10.0)
    assert back.rows.tobytes() == rows().tobytes()


def test_its_rows_are_checked_as_onsets_are() -> None:
    bad = rows()
    bad["velocity"][1] = 200
    with pytest.raises(ProtocolError, match=r"row 1\.velocity"):
        p.encode(p.Message(p.Kind.SHOWN_ONSET, bad))
    frames = p.encode(p.Message(p.Kind.SHOWN_ONSET, rows()))
    with pytest.raises(ProtocolError, match="payload"):
        p.decode([frames[0], frames[1][:30]])


def controls() -> np.ndarray:
    from livedrummer.timeline.events import CONTROL_DTYPE, ControlKind

    r = np.zeros(2, CONTROL_DTYPE)
    r["time_s"] = [10.5, 10.75]
    r["kind"] = [ControlKind.CHOKE, ControlKind.HIHAT_PEDAL]
    r["channel"], r["number"], r["value"] = 9, [49, 4], [127, 120]
    return r


def test_a_shown_control_round_trips_and_its_rows_are_checked_as_controls_are() -> None:
    msg = p.Message(
        p.Kind.SHOWN_CONTROL,
        controls(),
        performer=2,
        seq=8,
        send_time_s=10.0,
        stream=p.Stream.POSES,
    )
    frames = p.encode(msg)
    assert frames[0][:6] == p.topic(p.Kind.SHOWN_CONTROL) and frames[0][5] == 9
    back = p.decode(frames)
    assert back.kind is p.Kind.SHOWN_CONTROL and (back.performer, back.seq) == (2, 8)
    assert back.rows.tobytes() == controls().tobytes()
    bad = controls()
    bad["value"][0] = 128
    with pytest.raises(ProtocolError, match=r"row 0\.value"):
        p.encode(p.Message(p.Kind.SHOWN_CONTROL, bad))
    with pytest.raises(ProtocolError, match="needs a 1-d"):  # onset rows are not controls
        p.encode(p.Message(p.Kind.SHOWN_CONTROL, rows()))
