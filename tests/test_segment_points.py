"""path.Segment keeps a line's end points as floats until an array is asked for (issue 17, decision bench B156):
the run feed's line (`line_of`) is the segment `Segment.of` makes from the same move, bit for bit, whichever form
(array or list) a reader takes; a snap that sets one form replaces the other; the fitted spans that extend Segment
(SplineSpan, JoinedSpan) keep their fields through a pickle (the fit-ahead child sends them so, bench B98)."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np

from nc.motion.path import Segment
from nc.motion.spline_feed import RunFeed
from nc.motion.spline_runs import SplineSpan
from nc.moves import Move

AXES = ("X", "Y", "Z")


def _move(p: tuple[float, float, float], q: tuple[float, float, float]) -> Move:
    s, e = dict(zip(AXES, p)), dict(zip(AXES, q))
    return Move("line", 7, "G01", s, e, e, feed=1200.0)


def _run_feed_line(m: Move) -> Segment:
    feed = RunFeed.__new__(RunFeed)  # the geometry alone: line() reads the axes
    feed.axes = AXES
    assert feed.line(m) is not None
    _, a, b, n, u = feed.geom
    return Segment.line_of(AXES, a, b, n, u)


def test_the_run_feeds_line_is_segment_of_bit_for_bit():
    m = _move((0.1, 2.0 / 3.0, -5.25), (1.3, 0.7, -5.0))
    got, want = _run_feed_line(m), Segment.of(m, AXES)
    assert got.kind == want.kind == "line"
    assert got.length == want.length == math.dist([0.1, 2.0 / 3.0, -5.25], [1.3, 0.7, -5.0])
    assert got.start.tobytes() == want.start.tobytes() and got.end.tobytes() == want.end.tobytes()
    assert got.start.dtype == np.float64
    assert got.start_floats == want.start.tolist() and got.end_floats == want.end.tolist()
    assert got.tangent(False) == want.tangent(False) and got.direction_cosines() == want.direction_cosines()
    assert got.points(np.array([0.0, 0.4, got.length])).tobytes() == want.points(
        np.array([0.0, 0.4, want.length])).tobytes()


def test_setting_one_form_of_an_end_point_replaces_the_other():
    seg = Segment.of(_move((0.0, 0.0, 0.0), (3.0, 4.0, 0.0)), AXES)
    assert seg.start_floats == [0.0, 0.0, 0.0]
    seg.start_floats = [1e-7, 0.0, 0.0]  # a cruise's snap to where the last block ended
    assert seg.start.tolist() == [1e-7, 0.0, 0.0]
    seg.start = np.array([2e-7, 1e-7, 0.0])  # a plan's start at the present position
    assert seg.start_floats == [2e-7, 1e-7, 0.0]
    seg.end = np.array([3.0, 4.0, 1e-7])
    assert seg.end_floats == [3.0, 4.0, 1e-7]
    assert seg.end.tolist() == [3.0, 4.0, 1e-7]


def test_a_spline_span_keeps_its_fields_through_a_pickle():
    sp = SplineSpan(AXES, np.array([0.0, 1.0, 2.0]), np.array([0.5, 1.5, 2.0]), 0.75, "spline",
                    dir_bound=np.array([0.7, 0.7, 0.0]))
    sp.__dict__["_limits"] = ("caps",)  # what the planner keeps on a span (planner_runs._span_block)
    got = pickle.loads(pickle.dumps(sp, protocol=pickle.HIGHEST_PROTOCOL))
    assert type(got) is SplineSpan
    assert [f.name for f in dataclasses.fields(got)][:5] == ["axes", "start", "end", "length", "kind"]
    assert got.start.tolist() == [0.0, 1.0, 2.0] and got.end_floats == [0.5, 1.5, 2.0]
    assert (got.length, got.kind, got.axes) == (0.75, "spline", AXES)
    assert got.dir_bound.tolist() == [0.7, 0.7, 0.0] and got.__dict__["_limits"] == ("caps",)
    twin = dataclasses.replace(got, length=0.5)  # spline_join's JoinedSpan is made from the fields so
    assert twin.length == 0.5 and twin.start.tolist() == [0.0, 1.0, 2.0]
