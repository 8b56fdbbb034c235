"""benchmarks/bench_blend_bound.py: the clothoid-pair geometry it sizes blends with, checked against a
direct integration, and the bound it gives on two programs (decision motion 40)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks.bench_blend_bound import SHARE_N, bound
from nc.motion.clothoid import clothoid_pair
from benchmarks.bench_vs_linuxcnc import START, TOL, chord_circle, contour_90


def _pair_by_integration(theta: float, n: int = 200_001) -> tuple[float, float]:
    """The same pair built point by point: curvature rising linearly over unit length to theta,
    then falling back; tangent length and deviation read off the polyline it traces."""
    s = np.linspace(0.0, 2.0, n)
    kappa = np.where(s <= 1.0, theta * s, theta * (2.0 - s))
    phi = np.concatenate(([0.0], np.cumsum((kappa[1:] + kappa[:-1]) / 2.0 * np.diff(s))))
    dx, dy = np.cos(phi), np.sin(phi)
    x = np.concatenate(([0.0], np.cumsum((dx[1:] + dx[:-1]) / 2.0 * np.diff(s))))
    y = np.concatenate(([0.0], np.cumsum((dy[1:] + dy[:-1]) / 2.0 * np.diff(s))))
    # The legs: y = 0 (heading 0) and the line through the end point with heading theta; the vertex
    # is where they meet, and the tangent length is its distance from the start.
    ex, ey = x[-1], y[-1]
    t = ex - ey / math.tan(theta)
    # The deviation: the largest distance of the pair from the nearer leg.
    d1 = np.abs(y)
    d2 = np.abs(-(x - t) * math.sin(theta) + y * math.cos(theta))
    return t, float(np.max(np.minimum(d1, d2)))


@pytest.mark.parametrize("theta", [0.02, math.radians(15.0), math.pi / 2.0])
def test_clothoid_pair_matches_a_direct_integration(theta):
    t, dev = clothoid_pair(theta)
    ti, devi = _pair_by_integration(theta)
    assert t == pytest.approx(ti, rel=1e-5)
    assert dev == pytest.approx(devi, rel=1e-4)


def test_a_slight_turn_gives_the_small_angle_limits():
    # nearly straight: tangent length → L, deviation → L·theta/6
    t, dev = clothoid_pair(1e-4)
    assert t == pytest.approx(1.0, abs=1e-6)
    assert dev == pytest.approx(1e-4 / 6.0, rel=1e-3)


def test_bound_keeps_long_lines_at_feed_and_finds_dense_chords_slow():
    sq = contour_90()
    pts = np.array([START] + sq.points)
    b = bound(pts, sq.feed / 60.0, TOL, SHARE_N)
    # three 90° corners each cost a few ms at most; the lines run at feed
    assert sq.feed_limited() < b < sq.feed_limited() * 1.01
    c = chord_circle(10.0)
    b = bound(np.array([START] + c.points), c.feed / 60.0, TOL, 1.0)
    # blends bounded by half of a 0.05 mm chord change curvature fast: far slower than the feed
    assert b > 1.7 * c.feed_limited()


def test_blended_path_is_continuous_and_within_the_tolerance():
    from benchmarks.bench_blend_bound import blended_path, sample_path
    from benchmarks.bench_vs_linuxcnc import cam_polyline
    from tests.motion_helpers import polyline_deviation

    prog = cam_polyline(60)
    pts = np.array([START] + prog.points, dtype=float)
    pieces = blended_path(pts, TOL)
    ds = 0.001
    q = sample_path(pieces, ds * np.arange(int(sum(p.length for p in pieces) / ds)))
    step = np.linalg.norm(np.diff(q, axis=0), axis=1)
    assert step.max() <= ds * (1.0 + 1e-6) and step.min() >= ds * (1.0 - 1e-3)  # no jump, no stall
    u = np.diff(q, axis=0) / step[:, None]
    turn = np.arccos(np.clip((u[1:] * u[:-1]).sum(axis=1), -1.0, 1.0))
    assert turn.max() < 0.01  # tangent-continuous: the sharpest blend turns ≈ 2 mrad per µm here
    dev = polyline_deviation(q, pts)
    assert 0.9 * TOL < dev <= TOL * (1.0 + 1e-6)
