"""Fitted CAM runs in the planner (issue 18, decisions motion 56-58, nc.motion.spline_feed): runs of short feed
lines are held back, fitted within N1.053 and planned as spline spans, under the filter with its share λ = 0 on
them. Pinned on simulated time with the bench's limits (benches/mill-3axis.toml), every cycle within the axis
limits and the setpoints within N1.053 of the programmed polyline."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from benchmarks.bench_vs_linuxcnc import START, cam_polyline, cam_surface, chord_circle
from nc.motion.offline import run
from nc.moves import Move
from tests.motion_helpers import TOL, polyline_deviation, single_block_operator, worst_ratio
from tests.test_motion_cam import BENCH, moves
from hil.bench_file import load_bench_file


def _cfg(**kw):
    return dataclasses.replace(load_bench_file(BENCH).motion_config(), **kw)


def _checked(mv: list[Move], cfg, pts, on_cycle=None):
    st = run(mv, cfg, dict(zip("XYZ", START)), on_cycle=on_cycle)
    assert not st.alarms, st.alarms
    r = worst_ratio(st, cfg)
    assert r["v"] <= TOL and r["a"] <= TOL and r["j"] <= TOL, r
    assert polyline_deviation(st.positions, pts) <= cfg.path_tolerance + 1e-9
    return st


@pytest.mark.parametrize("make, measured", [(cam_polyline, 7.663), (cam_surface, 7.690)])
def test_a_fitted_cam_run_holds_the_feed(make, measured):
    """400 segments of ≈ 0.78 mm turning ≈ 15° (F2500): corner blends 8.583 s / 8.814 s (1.140× / 1.1885× the
    feed-limited 7.529 s / 7.416 s, decision 47); fitted and planned as spans, four a segment, 7.663 s / 7.690 s
    (1.018× / 1.037×, the filter's lag and settling included; one span a segment: 7.730 s / 7.795 s)."""
    prog = make(400)
    st = _checked(moves(prog), _cfg(), [START] + prog.points)
    assert st.state.value == "finished"
    assert st.time <= measured * 1.005 + 1e-9, st.time
    off = run(moves(prog), _cfg(fit_runs=False), dict(zip("XYZ", START)))
    assert st.time < 0.92 * off.time, (st.time, off.time)


def test_runs_that_do_not_pay_are_not_fitted():
    """A chord circle (its corners' own caps far above the feed) runs as before, bit for bit; and nothing is
    fitted without a tolerance (N1.053 = 0) or with the feature off."""
    prog = chord_circle(5.0)
    a = run(moves(prog), _cfg(), dict(zip("XYZ", START)))
    b = run(moves(prog), _cfg(fit_runs=False), dict(zip("XYZ", START)))
    assert np.array_equal(a.positions, b.positions)
    from nc.motion.planner import Planner
    assert Planner(_cfg(path_tolerance=None))._runs is None
    assert Planner(_cfg(fit_runs=False))._runs is None


def _polyline(n: int = 120):
    return [START] + cam_polyline(n).points


def _speed_at(st, pt) -> tuple[float, int]:
    """Least path speed of the output near the vertex pt, and the cycle closest to it."""
    d = np.linalg.norm(st.positions - np.array(pt), axis=1)
    k = int(np.argmin(d))
    v = np.linalg.norm(np.diff(st.positions, axis=0), axis=1) / st.cycle
    return float(v[max(k - 5, 0):k + 5].min()), k


def test_an_exact_stop_inside_a_run_stops_on_its_vertex():
    pts = _polyline()
    mv = moves(cam_polyline(120))
    mv[59] = mv[59].replaced(exact_stop=True)  # G09 on line 60
    st = _checked(mv, _cfg(), pts)
    v, k = _speed_at(st, pts[60])
    assert v < 1e-6 and np.linalg.norm(st.positions[k] - np.array(pts[60])) < 1e-6


def test_a_sharp_corner_inside_a_run_still_slows():
    pts = _polyline()
    # a 90° turn after vertex 60: the rest of the polyline turned about Z around it
    p = np.array(pts)
    c = p[60]
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    d = p[61] - c
    u = d / np.linalg.norm(d)
    ang = np.arctan2(u[1], u[0])
    r2 = np.array([[np.cos(-ang), -np.sin(-ang), 0.0], [np.sin(-ang), np.cos(-ang), 0.0], [0.0, 0.0, 1.0]])
    q = np.vstack([p[:61], c + ((p[61:] - c) @ r2.T) @ rot.T @ np.linalg.inv(r2).T])
    q = np.round(q, 3)
    prog = dataclasses.replace(cam_polyline(120), points=[tuple(x) for x in q[1:]])
    st = _checked(moves(prog), _cfg(), [tuple(x) for x in q])
    v, _ = _speed_at(st, q[60])
    assert v < 5.0, v  # the feed is 41.7 mm/s


@pytest.mark.parametrize("action", ["hold", "reset"])
def test_a_hold_or_a_reset_mid_run_stops_under_control(action):
    pts = _polyline()
    mv = moves(cam_polyline(120))
    seen = {}

    def hook(n, ch):
        if n == 900:
            ch.feed_hold() if action == "hold" else ch.reset()
            seen["at"] = ch.planner.output.copy()
        if action == "hold" and n == 1300:
            seen["rest"] = ch.planner.output.copy()
            ch.cycle_start()

    st = _checked(mv, _cfg(), pts, on_cycle=hook)
    # stopped within the braking distance of the spans' tangential limits (a_t ≈ 200-400 mm/s² at the cap: ≈ 3 mm
    # from 41.7 mm/s, the output 0.6 mm behind), then stood still
    i = 1300 if action == "hold" else len(st.positions) - 1
    assert np.linalg.norm(st.positions[i] - seen["at"]) < 4.5
    if action == "hold":
        assert np.array_equal(st.positions[i - 50], st.positions[i])
    if action == "hold":  # resumed and finished on the program's end point
        assert st.state.value == "finished"
        assert np.linalg.norm(st.positions[-1] - np.array(pts[-1])) < 1e-9
    else:
        assert st.state.value == "idle"


@pytest.mark.parametrize("inserts", [{}, {60: "M08", 100: "G04 P10"}])
def test_a_fitted_run_through_hil_run_stretched_equals_stepped(monkeypatch, tmp_path, inserts):
    """`hil run` (lock-step, the bench's basic MLC): the trace with stretches (decisions bench B20-B27) equals the
    cycle-by-cycle one column by column while runs are held back, fitted and let through (an M code and a
    dwell end a run: the channel closes the queue before them)."""
    from benchmarks.trace_ab import compare, one
    from hil.stretch import ENV
    from tests.test_stretch_reads import KW

    lines = cam_polyline(150).text(lcnc=False).splitlines()
    for at in sorted(inserts, reverse=True):
        lines.insert(at, inserts[at])
    prog = tmp_path / "cam.nc"
    prog.write_text("\n".join(lines) + "\n")
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), KW, tmp_path / f"{on}.parquet", kept))
    assert compare(out[0], out[1]) == []
    stepped, stretched = kept
    assert stretched.run.ok and stretched.run.stretched > 0.5 * stretched.run.cycles


def test_single_block_runs_a_held_back_move_at_once():
    """Single block: the channel reads one move and waits; the move a run holds back is let through (the
    channel reads nothing more), so each block stops on its own end point and the program finishes."""
    from nc.channel import RunState

    pts = _polyline(12)
    stops: list = []
    st = _checked(moves(cam_polyline(12)), _cfg(), pts, on_cycle=single_block_operator(stops))
    assert st.state is RunState.FINISHED
    assert np.allclose(stops, np.array(pts[1:]), atol=1e-9)
