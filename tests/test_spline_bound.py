"""Decision motion 48 (measured, not built): a curvature-continuous fit of a CAM run within N1.053 lets the
feed hold where corner blends cannot (benchmarks/bench_spline_bound.py)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_spline_bound import START, best_fit, bound, evaluate, through_planner
from benchmarks.bench_vs_linuxcnc import BENCH, cam_polyline, cam_surface
from hil.bench_file import load_bench_file
from nc.motion.spline_runs import LAM, fit_curve, samples
from tests.motion_helpers import TOL, polyline_deviation, worst_ratio


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_the_fit_keeps_the_tolerance_and_is_curvature_continuous(make):
    prog = make(120)
    pts = np.array([START] + prog.points, dtype=float)
    (spl, cum), _ = best_fit(pts, 0.02)
    uu = np.linspace(0.0, cum[-1], 20_000)
    cp = np.stack([s(uu) for s in spl], axis=1)
    assert 0.015 < polyline_deviation(cp, pts) <= 0.02  # the tolerance is used, not exceeded
    assert np.allclose(cp[0], pts[0], atol=1e-4) and np.allclose(cp[-1], pts[-1], atol=1e-4)
    # r'' is continuous across every knot (a cubic spline is C2): no curvature jump to stop at
    k = spl[0].k
    knots = spl[0].t[k + 1:-k - 1]
    eps = 1e-9
    for s in spl:
        d2 = s.derivative(2)
        assert np.max(np.abs(d2(knots + eps) - d2(knots - eps))) < 1e-4


@pytest.mark.parametrize("make, most", [(cam_polyline, 1.02), (cam_surface, 1.03)])
def test_a_fitted_run_holds_the_feed_where_corner_blends_cannot(make, most):
    """Corner blends: 1.140× / 1.1885× the feed-limited time (decision 47), and ≥ 1.064× / 1.115× whatever
    their speed planning. The fit's bound, with speed changes at 1000 mm/s² from rest to rest: 1.013× / 1.019×."""
    r = bound(make(400), 0.02, 0.8, 1000.0)
    assert r["dev"] <= 0.02
    assert r["limited"] / r["bound"] <= most, r
    assert r["v_p5"] >= 0.95 * 2500.0 / 60.0  # the feed nearly holds nearly everywhere (blends: 5 % ≤ 30 mm/s)


def test_the_fit_is_local_a_few_segments_ahead_fix_it():
    """What a streaming planner needs: the fit over a span no longer changes once 10 more segments are
    known (the quintic fit, λ = 0.01; the cubic one: 8 at λ = 0.1, 6 at λ = 0.01)."""
    pts = np.array([START] + cam_polyline(200).points, dtype=float)
    full, part, cum = fit_curve(pts, LAM), fit_curve(pts[:101], LAM), samples(pts)[2]
    uu = np.linspace(0.0, cum[90], 4000)
    assert max(np.abs(full[a](uu) - part[a](uu)).max() for a in range(3)) < 1e-6
    # and the derivatives the speed is planned on
    _, _, r2, r3, _ = evaluate(full, cum[-1])
    assert np.isfinite(r2).all() and np.isfinite(r3).all()


@pytest.mark.parametrize("make, time", [(cam_polyline, 2.352), (cam_surface, 2.363)])
def test_the_spans_through_the_planner_keep_the_limits_and_the_tolerance(make, time):
    """Decisions 50/51: the spans as blocks of today's planner (filter off): 120 segments in 2.352 s / 2.363 s
    (1.052× / 1.053× the feed-limited time, with the start and the stop; the cubic fit 2.407 / 2.363 s;
    corner blends: 1.14× / 1.19× on 400), every cycle within the axis limits and the setpoints within
    N1.053 of the programmed polyline."""
    prog = make(120)
    st = through_planner(prog, 0.02)
    assert st.state.value == "finished" and not st.alarms
    assert st.time == pytest.approx(time, abs=0.02)
    r = worst_ratio(st, load_bench_file(BENCH).motion_config())
    assert r["v"] <= TOL and r["a"] <= TOL and r["j"] <= TOL, r
    assert polyline_deviation(st.positions, [START] + prog.points) <= 0.02
