"""DeltaStamper: driver delta times anchored on the shared clock (pure logic)."""

from __future__ import annotations

import numpy as np

from livedrummer.midi.drivertime import MAX_LAG_S, DeltaStamper


def play(true_s: np.ndarray, read_s: np.ndarray) -> np.ndarray:
    st = DeltaStamper()
    deltas = np.diff(true_s, prepend=true_s[0])
    return np.array([st.stamp(float(d), float(r)) for d, r in zip(deltas, read_s, strict=True)])


def test_late_reads_do_not_move_the_stamps() -> None:
    rng = np.random.default_rng(1)
    true_s = 100.0 + np.cumsum(rng.uniform(0.001, 0.2, 2000))
    lag = rng.uniform(0.0, 0.0005, true_s.size)  # read within one poll interval ...
    lag[rng.random(true_s.size) < 0.2] += rng.uniform(0.005, 0.05, 1)  # ... or starved
    stamps = play(true_s, true_s + lag)
    err = stamps - true_s
    assert np.all(err >= -1e-9) and np.all(stamps <= true_s + lag + 1e-9)
    # After the first prompt read, every stamp is within the best lag seen so far.
    assert np.percentile(err[10:], 99) < 0.0005 and err[10:].max() < 0.0005
    assert np.percentile(lag, 99) > 0.005  # the reads themselves were far later
    assert np.all(np.diff(stamps) >= 0)


def test_a_slow_first_read_is_corrected_by_the_next_prompt_one() -> None:
    true_s = np.array([10.0, 10.5, 11.0, 11.5])
    read_s = true_s + np.array([0.030, 0.020, 0.0001, 0.010])
    stamps = play(true_s, read_s)
    assert stamps[0] == read_s[0]  # nothing better known yet
    np.testing.assert_allclose(stamps[2:], true_s[2:] + 0.0001, atol=1e-5)


def test_a_broken_timeline_restarts_on_the_read() -> None:
    st = DeltaStamper()
    st.stamp(0.0, 5.0)
    # The driver's sum says 0.1 s later, but the read comes 10 s later: deltas were lost.
    t = st.stamp(0.1, 15.0)
    assert t == 15.0 and st.resyncs == 1
    assert 15.0 - (5.0 + 0.1) > MAX_LAG_S
    assert abs(st.stamp(0.5, 15.5001) - 15.5) < 1e-5  # (the anchor ages 10 ppm: 5 µs)


def test_the_anchor_follows_a_slower_driver_clock() -> None:
    # The driver's clock runs 5 ppm slow: its deltas are short, reads drift later.
    true_s = np.arange(0.0, 3600.0, 0.5)
    driver = true_s * (1 - 5e-6)
    st = DeltaStamper()
    deltas = np.diff(driver, prepend=driver[0])
    stamps = np.array(
        [st.stamp(float(d), float(r) + 0.0002) for d, r in zip(deltas, true_s, strict=True)]
    )
    assert abs(stamps[-1] - true_s[-1]) < 0.001  # an hour later, still within 1 ms
