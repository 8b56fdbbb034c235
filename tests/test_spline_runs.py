"""nc.motion.spline_runs (decision motion 49): a CAM run fitted within N1.053 by one C2 curve, cut into
spans at the vertices; each span read off its own points, and its limits against every axis' own."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_vs_linuxcnc import START, cam_polyline, cam_surface
from nc.motion.spline_runs import Cost, FitError, fit_run, polyline_distance, span_limits, spans
from tests import spline_slow as slow
from tests.motion_helpers import polyline_deviation

AXES = ("X", "Y", "Z")
VEL = np.array([500.0, 500.0, 300.0])
ACC = np.array([5000.0, 5000.0, 3000.0])
JERK = np.array([250_000.0, 250_000.0, 150_000.0])


def _spans(make, n: int = 50):
    pts = np.array([START] + make(n).points, dtype=float)
    spl, cum = fit_run(pts, 0.02)
    return pts, spans(spl, cum, AXES)


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_spans_join_in_position_tangent_and_curvature_within_the_tolerance(make):
    pts, sp = _spans(make)
    assert len(sp) == len(pts) - 1 and all(s.kind == "spline" for s in sp)
    assert np.allclose(sp[0].start, pts[0], atol=1e-4) and np.allclose(sp[-1].end, pts[-1], atol=1e-4)
    for a, b in zip(sp[:-1], sp[1:]):
        assert np.allclose(a.end, b.start, atol=1e-9)
        assert np.allclose(a.unit_tangent(True), b.unit_tangent(False), atol=1e-7)
        assert np.allclose(a.curvature_vector(True), b.curvature_vector(False), atol=1e-5)
    every = np.vstack([s.points(np.linspace(0.0, s.length, 300)) for s in sp])
    assert 0.015 < polyline_deviation(every, pts) <= 0.02


def test_a_span_is_parametrised_by_its_arc_length_and_its_derivatives_are_its_own():
    _, sp = _spans(cam_surface)
    for s in sp[5:45:8]:
        ss = np.linspace(0.0, s.length, 4001)
        p, rs, rss, rsss = s.derivatives(ss)
        assert np.abs(s.points(ss) - p).max() < 1e-9  # the pieces' polynomials in s against the Newton steps
        h = ss[1] - ss[0]
        step = np.linalg.norm(np.diff(p, axis=0), axis=1) / h
        assert np.abs(step - 1.0).max() < 1e-5  # unit speed in s: the planner's v is the path speed
        assert np.allclose(np.linalg.norm(rs, axis=1), 1.0, atol=1e-9)
        fd2 = np.diff(p, 2, axis=0) / h ** 2
        assert np.abs(fd2 - rss[1:-1]).max() < 1e-3 * max(1.0, np.abs(rss).max())
        # r''' jumps at the pieces' knots: compare its integral with r'' (trapezoid)
        integ = np.cumsum(0.5 * (rsss[1:] + rsss[:-1]) * h, axis=0)
        assert np.abs(integ - (rss[1:] - rss[0])).max() < 1e-4 * max(1.0, np.abs(rss).max())  # 3e-5; a term off: 2-9e-4
        assert np.all(np.abs(rsss).max(axis=0) <= s.jerk_bound + 1e-9)
        assert np.all(np.abs(rss).max(axis=0) <= s.acc_bound + 1e-9)


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_span_limits_keep_every_axis_within_its_limits(make):
    """At the cap and below it, with a_t = ±a and j_t = ±j: acceleration a_t·r' + v²·r'' and jerk
    j_t·r' + 3·v·a_t·r'' + v³·r''' on every axis within its limit, read off the span's own derivatives."""
    _, sp = _spans(make)
    worst = 0.0
    for s in sp:
        v, a, j = span_limits(s, VEL, ACC, JERK)
        assert v > 0.0 and a > 0.0 and j > 0.0
        _, rs, rss, rsss = s.derivatives(np.linspace(0.0, s.length, 400))
        for f in (1.0, 0.6):
            u = f * v
            assert np.all(np.abs(u * rs) <= VEL * (1.0 + 1e-9))
            for sa in (-1.0, 1.0):
                assert np.all(np.abs(sa * a * rs + u * u * rss) <= ACC * (1.0 + 1e-9))
                for sj in (-1.0, 1.0):
                    jx = np.abs(sj * j * rs + 3.0 * u * sa * a * rss + u ** 3 * rsss).max(axis=0)
                    assert np.all(jx <= JERK * (1.0 + 1e-9)), (jx / JERK)
                    worst = max(worst, float(np.max(jx / JERK)))
    assert worst > 0.7  # the budget is used


def test_the_quintic_fit_lets_the_spans_run_faster_than_the_cubic():
    """Decision 51: the penalty on r''' (quintic) instead of r'' (cubic) leaves no jumps of r''' at the knots:
    one cap a span, Σ length / min(F, cap) over 120 segments of the CAM polyline 1.0014× against 1.018×."""
    pts = np.array([START] + cam_polyline(120).points, dtype=float)
    feed = 2500.0 / 60.0
    bound = cam_polyline(120).feed_limited()
    t = {}
    for degree, lam in ((3, 0.1), (5, 0.01)):
        cut = spans(*fit_run(pts, 0.02, lam=lam, degree=degree), AXES)
        t[degree] = sum(s.length / min(span_limits(s, VEL, ACC, JERK)[0], feed) for s in cut) / bound
    assert t[5] <= 1.005 < 1.01 <= t[3], t


def _window(make, at: int = 100, n: int = 40) -> np.ndarray:
    """A streaming planner's window: `n` segments of a CAM program from vertex `at` on."""
    return np.array([START] + make(at + n + 1).points, dtype=float)[at:at + n + 1]


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_the_fast_fit_is_the_slow_one_within_its_finer_look(make):
    """Decision 53: the banded solve, the check's exact distances only where they can reach 0.9·tol and its
    finer look only where the nearest segment changes give the slow reference's curve (one sparse solve a
    round, every fine point; tests/spline_slow.py) within 1e-5 mm (2e-6 on these windows, the finer look's
    points between a step's ends no longer read where the distance is smooth) in as many rounds, and the
    curve keeps N1.053 read 20 times finer than the check."""
    pts = _window(make)
    cost = Cost(parts={})
    spl, cum = fit_run(pts, 0.02, cost=cost)
    ref, _, rounds = slow.fit_run(pts, 0.02)
    assert cost.rounds == rounds > 1
    uu = np.linspace(0.0, cum[-1], 20_000)
    assert max(np.abs(a(uu) - b(uu)).max() for a, b in zip(spl, ref)) < 1e-5
    curve = np.stack([s(uu) for s in spl], axis=1)
    assert 0.015 < polyline_deviation(curve, pts) <= 0.02
    assert set(cost.parts) == {"setup", "solve", "check", "weights"}


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_the_spans_cut_at_once_are_the_spans_cut_one_by_one(make):
    """Decision 53: every piece of the run in one batch, the same arithmetic: lengths, arc-length tables,
    and points through Newton steps as the spans cut one by one (tests/spline_slow.py) to 1e-12; r(s)'s
    polynomials (a fixed inverse Vandermonde matrix instead of a solve a piece) to 1e-10 mm (2e-11 here); the
    ends and the bounds, read where each piece's w(s) polynomial puts the samples instead of Newton steps, to
    1e-10 (4e-12 relative, 2e-12 mm here)."""
    spl, cum = fit_run(_window(make), 0.02)
    fast, ref = spans(spl, cum, AXES), slow.spans(spl, cum)
    assert len(fast) == len(ref) == len(cum) - 1
    for f, r in zip(fast, ref):
        assert f.length == pytest.approx(r.length, abs=1e-12)
        assert np.allclose(f.s_tab, r.s_tab, rtol=0.0, atol=1e-12)
        ss = np.linspace(0.0, r.length, 97)
        for a, b in zip(f.derivatives(ss), r.derivatives(ss)):
            assert np.abs(a - b).max() <= 1e-12 * max(1.0, np.abs(b).max())
        p = r.derivatives(np.array([0.0, r.length]))[0]
        assert np.abs(f.start - p[0]).max() < 1e-10 and np.abs(f.end - p[1]).max() < 1e-10
        assert np.abs(f.points(ss) - r.derivatives(ss)[0]).max() < 1e-9
        assert np.allclose(f.s_poly, r.s_poly(), rtol=0.0, atol=1e-10)
        for a, b in zip((f.dir_bound, f.acc_bound, f.jerk_bound), r.bounds()):
            assert np.allclose(a, b, rtol=1e-10, atol=0.0)


def test_the_distance_skips_only_segments_that_cannot_be_nearer():
    """Decision 53: polyline_distance measures the segments two away only where their bounding spheres allow
    them to be nearer; on points near a polyline of 0.003-2 mm segments, turning sharply, it equals the
    measure against all five (tests/spline_slow.py) to rounding (measuring only three: off by up to 0.06 mm)."""
    rng = np.random.default_rng(3)
    d = rng.normal(0.0, 1.0, (60, 3))
    d[1:] += 0.3 * d[:-1]
    steps = d / np.linalg.norm(d, axis=1)[:, None] * rng.choice([0.003, 0.05, 0.78, 2.0], 60)[:, None]
    pts = np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(steps, axis=1))])
    cu = np.sort(rng.uniform(0.0, cum[-1], 5000))
    k = np.clip(np.searchsorted(cum, cu) - 1, 0, 59)
    f = (cu - cum[k]) / (cum[k + 1] - cum[k])
    curve = pts[k] + f[:, None] * steps[k] + rng.normal(0.0, 0.03, (5000, 3))
    assert np.abs(polyline_distance(curve, cu, pts, cum) - slow.distance(curve, cu, pts, cum)).max() < 1e-12


@pytest.mark.parametrize("pts", [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.1, 0.0]],
                                 [[0.0, 0.0, 0.0]], [[0.0, 0.0, 0.0], [1.0, np.nan, 0.0], [2.0, 0.0, 0.0]]])
def test_a_run_the_fit_cannot_take_is_a_fit_error(pts):
    """A vertex twice (decision 51's spans failed on it with an IndexError), one vertex, a NaN: FitError, which
    the caller answers with lines, not an exception of numpy's."""
    with pytest.raises(FitError):
        fit_run(np.array(pts), 0.02)


@pytest.mark.parametrize("make", [cam_polyline, cam_surface])
def test_the_end_tangents_worked_out_at_cut_are_the_spans_own(make):
    """`spans` works out every span's end tangent and curvature at once (the look-ahead reads them at every
    junction check); they are what the span's own derivatives give at s = 0 and s = length, to an ulp or two
    (numpy's batched sums)."""
    _, sp = _spans(make, 40)
    for s in sp:
        for at_end in (False, True):
            d = s.derivatives(np.array([s.length if at_end else 0.0]))
            assert np.allclose(s.unit_tangent(at_end), d[1][0], rtol=0.0, atol=1e-15)
            assert np.allclose(s.curvature_vector(at_end), d[2][0], rtol=0.0, atol=1e-15)
