"""BehindCounter: totals, and at most one warning line per window (pure logic)."""

from livedrummer.live.behind import BehindCounter


def test_one_line_per_window_and_the_totals() -> None:
    c = BehindCounter("late contacts", "raise --delay-ms", window_s=10.0)
    lines = [c.first(2, 0.0)]
    lines += [c.add(1, t * 0.5) for t in range(1, 20)]  # 9.5 s of one late contact each 0.5 s
    lines.append(c.add(1, 10.0))
    said = [x for x in lines if x is not None]
    assert said[0].startswith("2 late contacts (the first")
    assert said[1] == "22 late contacts in the last 10 s (22 so far); raise --delay-ms"
    assert len(said) == 2 and c.total == 22
    assert c.poll(30.0) is None  # a quiet window says nothing
    assert c.add(0, 31.0) is None


def test_nothing_late_says_nothing() -> None:
    c = BehindCounter("repeated frames")
    assert all(c.add(0, float(t)) is None for t in range(100)) and c.total == 0
