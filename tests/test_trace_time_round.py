"""The trace's time column of a bulk stretch (hil/stretch_bulk._round9): round(t, 9) of each cycle's time, worked out
in numpy where that is provably the same, must equal Python's round(t, 9) bit for bit: times summed cycle by cycle
as the runner sums them, ties and times past the fast path's range included."""

from itertools import accumulate, repeat
from operator import add

from hil.stretch_bulk import _round9


def _times(dt: float, n: int, start: float = 0.0) -> list[float]:
    return list(accumulate(repeat(dt, n), add, initial=start))[1:]


def test_cycle_times_round_as_python_rounds_them() -> None:
    for dt in (0.001, 0.0005, 0.00025, 0.004, 0.000125):
        ts = _times(dt, 200_000)
        got = _round9(ts)
        assert got == [round(t, 9) for t in ts]
        assert all(type(x) is float for x in got[:5])
    # a run that went on for hours (the fast path's range ends near 9.8 h): the same values past it
    ts = _times(0.001, 5_000, start=35_180.0)
    assert _round9(ts) == [round(t, 9) for t in ts]


def test_near_halfway_times_round_as_python_rounds_them() -> None:
    ts = [5e-10, 1.5e-9, 2.5e-9, 0.1234567895, 1e-12, 0.0]
    assert _round9(ts) == [round(t, 9) for t in ts]
    assert _round9(ts)[:3] == [1e-9, 1e-9, 3e-9]  # (5e-10 is a little over half a nanosecond in binary)
    assert _round9([]) == []
