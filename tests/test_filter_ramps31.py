"""The filter stop's path check (nc.motion.filter_ramps `polyline_distance`, decision bench B185): summed over the
axes one (rows, segments) array at a time, it gives the distances the (rows, segments, 3) form before it gave, bit for
bit, on random outputs and polylines with repeated points (zero-length segments, where the projection divides by
1e-30), signed zeros and far points; and a point on the polyline is at distance 0, one beside a segment at its normal
distance."""

from __future__ import annotations

import numpy as np

from nc.motion.filter_ramps import polyline_distance


def _before(q: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """polyline_distance as it was before B185, the reference."""
    a, d = pts[:-1], np.diff(pts, axis=0)
    l2 = np.maximum((d * d).sum(1), 1e-30)
    t = np.clip(((q[:, None, :] - a[None]) * d[None]).sum(2) / l2, 0.0, 1.0)
    return np.sqrt((((a[None] + t[..., None] * d[None]) - q[:, None, :]) ** 2).sum(2)).min(1)


def test_the_distances_are_the_reference_doubles() -> None:
    rng = np.random.default_rng(31)
    for _ in range(400):
        axes = int(rng.choice([2, 3, 4]))
        q = rng.standard_normal((int(rng.integers(1, 80)), axes)) * rng.choice([1e-4, 1.0, 1e3])
        pts = rng.standard_normal((int(rng.integers(2, 60)), axes)) * rng.choice([1e-4, 1.0, 1e3])
        rep = rng.random(len(pts)) < 0.3
        pts[1:][rep[1:]] = pts[:-1][rep[1:]]  # repeated points: zero-length segments
        pts[rng.random(len(pts)) < 0.1] = -0.0
        q[rng.random(len(q)) < 0.1] = pts[0]  # on a vertex: distance 0
        got, want = polyline_distance(q, pts), _before(q, pts)
        assert got.shape == want.shape == (len(q),)
        assert np.array_equal(got.view(np.int64), want.view(np.int64))  # the same doubles, signed zeros too


def test_a_point_on_the_path_is_at_zero_and_one_beside_it_at_its_normal_distance() -> None:
    pts = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 5.0, 0.0]])
    q = np.array([[4.0, 0.0, 0.0], [4.0, 0.003, 0.0], [10.002, 2.5, 0.0], [12.0, 8.0, 0.0]])
    got = polyline_distance(q, pts)
    assert got[0] == 0.0
    assert abs(got[1] - 0.003) < 1e-15 and abs(got[2] - 0.002) < 1e-12
    assert abs(got[3] - np.hypot(2.0, 3.0)) < 1e-12  # past the last vertex: to the vertex
