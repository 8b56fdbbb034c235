"""PositionFilter's share λ (decision motion 43): out = p(t − D) + λ·(F(p) − p(t − D)); bit for bit
today's filter at λ = 1, a pure delay at λ = 0, push and push_many alike; and decision 40 f's finding
that a ramp of λ must take 30 ms or more."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.bench_blend_bound import crossfade_run, share_ramps
from benchmarks.bench_vs_linuxcnc import LIMITS, cam_polyline
from nc.motion.smoothing import PositionFilter, smoothstep


def _path(seed: int = 3, n: int = 600) -> np.ndarray:
    """A jerky 3-axis walk with standstills (repeated rows: the still count and the snap at rest)."""
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.normal(0.0, 0.05, (n, 3)), axis=0)
    x[200:260] = x[199]  # long enough for the filter to settle
    x[400:405] = x[399]
    return x


def _one_by_one(f: PositionFilter, xs: np.ndarray, lam) -> np.ndarray:
    return np.array([f.push(x, float(l)) for x, l in zip(xs, lam)])


def test_lambda_one_is_todays_filter_bit_for_bit():
    xs = _path()
    ref = PositionFilter(16, 16, xs[0]).push_many(xs)
    assert np.array_equal(PositionFilter(16, 16, xs[0]).push_many(xs, np.ones(len(xs))), ref)
    assert np.array_equal(_one_by_one(PositionFilter(16, 16, xs[0]), xs, np.ones(len(xs))), ref)


def test_lambda_zero_is_the_input_delayed_by_the_group_delay():
    xs = _path()
    for n1, n2 in ((16, 16), (20, 12), (9, 7)):
        f = PositionFilter(n1, n2, xs[0])
        d = f.lag
        assert d == (n1 + n2 - 2) // 2
        out = f.push_many(xs, np.zeros(len(xs)))
        want = np.vstack([np.repeat(xs[:1], d, axis=0), xs[:-d]])
        assert np.array_equal(out, want)


def test_a_ramped_share_is_the_same_row_by_row_and_in_stretches():
    xs = _path(seed=5)
    lam = 1.0 - smoothstep((np.arange(len(xs)) - 100) / 30.0) + smoothstep((np.arange(len(xs)) - 450) / 30.0)
    a = PositionFilter(16, 16, xs[0]).push_many(xs, lam)
    b = _one_by_one(PositionFilter(16, 16, xs[0]), xs, lam)
    assert np.array_equal(a, b)
    f = PositionFilter(16, 16, xs[0])
    c = np.vstack([f.push_many(xs[:137], lam[:137]), f.push_many(xs[137:], lam[137:])])
    assert np.array_equal(a, c)
    whole = PositionFilter(16, 16, xs[0]).push_many(xs)
    assert not np.allclose(a[150:400], whole[150:400], atol=1e-6)  # it did act


def test_without_a_whole_cycle_delay_the_share_is_ignored():
    xs = _path()
    for n1, n2 in ((16, 15), (12, 20)):  # odd sum: D is half a cycle; n2 > n1: w1 does not reach back D
        f = PositionFilter(n1, n2, xs[0])
        assert f.lag is None
        assert np.array_equal(f.push_many(xs, np.zeros(len(xs))), PositionFilter(n1, n2, xs[0]).push_many(xs))


def _jerk_share(q: np.ndarray) -> float:
    j = np.diff(q, n=3, axis=0) / 1e-9
    return float((np.abs(j).max(axis=0) / LIMITS[:, 2]).max())


@pytest.mark.parametrize("r, lo, hi", [(15, 0.5, 0.7), (30, 0.2, 0.3)])
def test_a_share_ramp_takes_thirty_ms_on_a_blended_polyline(r, lo, hi):
    """Decision 40 f: the blended 400-segment CAM polyline at 25 mm/s, λ 1 → 0 at cycle 1000: a 15 ms
    ramp makes jerk (0.58 of the limit where the raw path has 0.20), a 30 ms one does not (0.24)."""
    prog = cam_polyline(400)
    raw, out = crossfade_run(prog, 25.0, share_ramps(40_000, r))
    assert lo < _jerk_share(out[960:1040 + r]) < hi
    assert _jerk_share(raw[960 - 15:1070 - 15]) < 0.21
