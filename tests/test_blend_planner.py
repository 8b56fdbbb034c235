"""Corner blends in the look-ahead (decision motion 42): with no position filter and a path tolerance,
line-line corners get a clothoid pair where it is faster; timings on simulated time, the tolerance
against the programmed polyline, every cycle within the axis limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.bench_vs_linuxcnc import START, cam_polyline, chord_circle
from nc.channel import RunState
from nc.motion import AxisLimits, MotionConfig
from nc.motion.offline import run
from nc.motion.planner import Planner
from tests.motion_helpers import AX, arc, check, lines, polyline_deviation, worst_ratio

TOL = 0.02
LIM = {"X": AxisLimits(500, 5000, 250_000), "Y": AxisLimits(500, 5000, 250_000), "Z": AxisLimits(300, 3000, 150_000)}


def _cfg(**kw) -> MotionConfig:
    kw.setdefault("fit_runs", False)  # corner blends, not fitted runs (those: tests/test_spline_feed.py)
    return MotionConfig(axes=AX, limits=LIM, **kw)


def test_a_cam_polyline_runs_blended_within_the_tolerance_and_the_limits():
    prog = cam_polyline(200)
    pts = [START] + prog.points
    st = check(lines(pts, prog.feed), _cfg(path_tolerance=TOL), START)
    dev = polyline_deviation(st.positions, pts)
    assert 0.9 * TOL < dev <= TOL * (1.0 + 1e-6)  # the blends use the tolerance, no more
    # 4.262 s blended (1.14x its 3.724 s feed-limited time), 4.182 s with decision 47's jerk budget;
    # every corner a near-stop without: 11.223 s
    assert st.time == pytest.approx(4.182, abs=0.03)
    st0 = check(lines(pts, prog.feed), _cfg(), START)  # no tolerance: no blend, the corners as before
    assert polyline_deviation(st0.positions, pts) < 1e-6 and st0.time > 2.0 * st.time


def test_a_chord_circle_is_blended_at_its_chords_half():
    prog = chord_circle(10.0)
    pts = [START] + prog.points
    st = check(lines(pts, prog.feed), _cfg(path_tolerance=TOL), START)
    # the half rule bounds the blends of 0.05 mm chords: they deviate a few µm from the chords, except
    # at the lead-in's 90° corner, which stays a stop (its blend would be slower, below)
    assert polyline_deviation(st.positions, pts) < 0.006
    assert st.time == pytest.approx(4.279, abs=0.03)  # 15.962 s without blends; 4.423 s before decision 47


def test_a_right_angle_between_long_lines_is_not_blended_a_stop_is_faster():
    pts = [(0, 0, 0), (100, 0, 0), (100, 100, 0)]
    st = check(lines(pts, 6000.0), _cfg(path_tolerance=TOL))
    st0 = check(lines(pts, 6000.0), _cfg())
    assert polyline_deviation(st.positions, pts) < 1e-9
    assert np.array_equal(st.positions, st0.positions)


def test_exact_stop_and_rapids_get_no_blend():
    pts = [(0, 0, 0), (3, 0, 0), (6, 0.8, 0), (9, 0, 0)]
    for moves in (lines(pts, 3000.0, exact_stop=True), lines(pts, None, kind="rapid")):
        st = check(moves, _cfg(path_tolerance=TOL))
        assert polyline_deviation(st.positions, pts) < 1e-9
    st = check(lines(pts, 3000.0), _cfg(path_tolerance=TOL))
    assert 0.5 * TOL < polyline_deviation(st.positions, pts) <= TOL * (1 + 1e-6)


def _filtered(**kw) -> MotionConfig:
    return _cfg(path_tolerance=TOL, filter_time=0.016, filter_scurve=0.016, min_segment_cycles=0.25, **kw)


def test_under_the_filter_a_cam_polyline_is_blended_where_its_share_is_zero():
    """Decision 45: the bench's 16 + 16 ms filter gives way (λ = 0) on the blended stretch."""
    prog = cam_polyline(200)
    pts = [START] + prog.points
    st = check(lines(pts, prog.feed), _filtered(), START)
    assert 0.9 * TOL < polyline_deviation(st.positions, pts) <= TOL * (1.0 + 1e-6)
    # 5.444 s with the filter's own corners (before); 4.292 s before decision 47's jerk budget
    assert st.time == pytest.approx(4.212, abs=0.03)


def test_under_the_filter_chords_keep_the_filters_corners():
    """A blend within half a 0.05 mm chord is slower than the filter's corner (decision 40 a): none is built,
    and nothing changes (R10 1.555 s, decision 39's figure; 1.516 s since the filter shapes the start, the speed-up
    out of the lead-in's corner and the stop, decision 52)."""
    prog = chord_circle(10.0)
    pts = [START] + prog.points
    pl = Planner(_filtered(), dict(zip(AX, START)))
    for m in lines(pts, prog.feed):
        pl.push(m)
    assert all(b.seg.kind == "line" for b in pl.blocks)
    st = check(lines(pts, prog.feed), _filtered(), START)
    assert st.time == pytest.approx(1.516, abs=0.003)


def test_without_a_whole_cycle_group_delay_the_filter_keeps_its_corners():
    prog = cam_polyline(60)
    pl = Planner(_cfg(path_tolerance=TOL, filter_time=0.016, filter_scurve=0.015), dict(zip(AX, START)))
    for m in lines([START] + prog.points, prog.feed):
        pl.push(m)
    assert all(b.seg.kind == "line" for b in pl.blocks)


def test_a_reversal_and_an_arc_after_a_blended_stretch_stay_within_the_limits():
    """Junctions the filter would round, within a blended stretch's reach, are taken as without it."""
    prog = cam_polyline(200)
    p = [np.array(x, float) for x in ([START] + prog.points)[:60]]
    d = (p[-1] - p[-2]) / np.linalg.norm(p[-1] - p[-2])
    turn = p[-1] - 2.0 * d + np.array([0.3, 0.0, 0.0])  # ≈ 170°
    e = turn + np.array([2.0, 0.0, 0.0])
    mv = lines(p + [turn], prog.feed)
    mv.append(arc(turn, e, (turn[0] + 1.0, turn[1]), "cw", prog.feed, line=200))
    tail = [e, e + np.array([0.0, 3.0, 0.0]), e + np.array([1.0, 5.0, 0.2])]
    mv += lines(tail, prog.feed, first_line=201)
    st = check(mv, _filtered(), START)
    assert polyline_deviation(st.positions[: int(np.argmax(st.lines >= 60))], p + [turn]) <= TOL * (1.0 + 1e-6)
    assert np.allclose(st.positions[-1], tail[-1], atol=1e-9)


def test_blend_blocks_carry_the_incoming_line_and_shorten_both_lines():
    pts = [(0, 0, 0), (2, 0, 0), (4, 0.5, 0), (6, 0, 0)]
    pl = Planner(_cfg(path_tolerance=TOL), dict(zip(AX, pts[0])))
    for m in lines(pts, 2500.0):
        pl.push(m)
    kinds = [(b.seg.kind, b.move.line) for b in pl.blocks]
    assert kinds == [("line", 1), ("blend", 1), ("line", 2), ("blend", 2), ("line", 3)]
    total = sum(b.length for b in pl.blocks)
    assert total < math.dist(pts[0], pts[1]) + math.dist(pts[1], pts[2]) + math.dist(pts[2], pts[3])
    for b1, b2 in zip(list(pl.blocks)[:-1], list(pl.blocks)[1:]):
        assert np.allclose(b1.seg.points(np.array([b1.length]))[0], b2.seg.points(np.array([0.0]))[0], atol=1e-12)
    st = run(lines(pts, 2500.0), _cfg(path_tolerance=TOL), dict(zip(AX, pts[0])))
    assert list(dict.fromkeys(st.lines.tolist())) == [0, 1, 2, 3]  # each program line once, in order


def test_feed_hold_on_a_blended_path_stops_and_resumes_within_the_limits():
    prog = cam_polyline(60)
    pts = [START] + prog.points
    cfg = _cfg(path_tolerance=TOL)
    seen = {}

    def ctl(n, ch):
        if n == 400:
            ch.feed_hold()
        if n == 700:
            seen["state"] = ch.state
            ch.cycle_start()

    st = run(lines(pts, prog.feed), cfg, dict(zip(AX, START)), on_cycle=ctl)
    assert seen["state"] is RunState.HOLD and st.state is RunState.FINISHED
    assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6
    assert polyline_deviation(st.positions, pts) <= TOL * (1.0 + 1e-6)
    assert np.allclose(st.positions[-1], pts[-1], atol=1e-9)
