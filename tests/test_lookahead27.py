"""The look-ahead's typed steps (nc.motion.lookahead; decision bench B148) give the floats the Python before them gave,
bit for bit: `reach` with C's sqrt and cbrt, `fastest_state`'s bisection on C doubles, `Limits.block_limits`' axis
loop, on random inputs; and a negative square root still raises math.sqrt's ValueError (C's sqrt alone would give a
NaN the passes would carry on with)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion import AxisLimits, MotionConfig
from nc.motion.lookahead import Limits, fastest_state, max_speed_at, reach
from nc.motion.path import Segment
from nc.moves import Move

AX = ("X", "Y", "Z")
LIM = {"X": AxisLimits(500, 5000, 250_000), "Y": AxisLimits(500, 5000, 250_000), "Z": AxisLimits(300, 3000, 150_000)}


def _reach_before(v0: float, length: float, a: float, j: float) -> float:
    """reach as it was before B148 (math's sqrt and cbrt on Python floats), the reference."""
    if length <= 0.0:
        return v0
    q = length * math.sqrt(j)
    p = 2.0 * v0
    disc = math.sqrt(q * q / 4.0 + p ** 3 / 27.0)
    x = math.cbrt(q / 2.0 + disc) + math.cbrt(q / 2.0 - disc)
    dv = x * x
    if dv * j <= a * a:
        return v0 + dv
    qa = 1.0 / a
    qb = 2.0 * v0 / a + a / j
    qc = 2.0 * v0 * a / j - 2.0 * length
    dv = (-qb + math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)
    return v0 + (0.0 if 0.0 > dv else dv)


def _fastest_before(v0: float, a0: float, d: float, a: float, j: float) -> tuple[float, float]:
    """fastest_state as it was before B148, the reference."""
    a0 = a0 if a0 < a else a
    t1 = (a - a0) / j
    d1 = v0 * t1 + a0 * t1 * t1 / 2.0 + j * t1 ** 3 / 6.0
    if d >= d1:
        v1 = v0 + a0 * t1 + j * t1 * t1 / 2.0
        return math.sqrt(v1 * v1 + 2.0 * a * (d - d1)), a
    lo, hi = 0.0, t1
    for _ in range(40):
        t = 0.5 * (lo + hi)
        if v0 * t + a0 * t * t / 2.0 + j * t ** 3 / 6.0 < d:
            lo = t
        else:
            hi = t
    return v0 + a0 * hi + j * hi * hi / 2.0, a0 + j * hi


def test_reach_and_fastest_state_as_before_bit_for_bit() -> None:
    rng = np.random.default_rng(148)
    for _ in range(3000):
        v0 = float(rng.uniform(0.0, 200.0)) * float(rng.integers(0, 2))  # from rest half the time
        length = float(10.0 ** rng.uniform(-4.0, 2.0))
        a = float(10.0 ** rng.uniform(2.0, 4.0))
        j = float(10.0 ** rng.uniform(4.0, 6.0))
        assert reach(v0, length, a, j).hex() == _reach_before(v0, length, a, j).hex()
        a0 = float(rng.uniform(-a, 1.2 * a))
        d = float(10.0 ** rng.uniform(-5.0, 1.0))
        got, want = fastest_state(v0, a0, d, a, j), _fastest_before(v0, a0, d, a, j)
        assert (got[0].hex(), got[1].hex()) == (want[0].hex(), want[1].hex())
        assert max_speed_at(v0, a0, d, a, j).hex() == want[0].hex()


def test_negative_square_root_raises_as_math_sqrt() -> None:
    with pytest.raises(ValueError, match="math domain error"):
        reach(1.0, 1.0, 1000.0, -1.0)  # √j of a negative jerk
    with pytest.raises(ValueError, match="math domain error"):
        fastest_state(1.0, 0.0, 10.0, -1.0, 1.0e5)  # a negative acceleration: v1² + 2·a·d below 0


def _block_limits_before(lim: Limits, seg: Segment) -> tuple[float, float, float]:
    """block_limits' line path (CUT, no N1.034/N1.035, no filter) as it was before B148: zip over the axes."""
    cfg = lim.cfg
    v = a = j = math.inf
    for d, vl, al, jl in zip(seg.direction_cosines(), lim._v, lim._acc, lim._jerk):
        if d > 1e-12:
            v, a, j = min(v, vl / d), min(a, al / d), min(j, jl / d)
    if v == math.inf:
        return 0.0, 1.0, 1.0
    a *= cfg.share_tangential
    j *= cfg.share_tangential
    return min(v, seg.length / (cfg.min_segment_cycles * lim.T)), a, j


def _line(p: np.ndarray, q: np.ndarray) -> Segment:
    s, e = dict(zip(AX, map(float, p))), dict(zip(AX, map(float, q)))
    return Segment.of(Move("line", 1, "", s, e, e, feed=3000.0, plane=("X", "Y")), AX)


def test_line_limits_as_before_bit_for_bit() -> None:
    """Random 3-axis lines, a zero component (no projection) now and then: the caps as zip and min() gave them."""
    lim = Limits(MotionConfig(axes=AX, limits=LIM))
    rng = np.random.default_rng(149)
    pts = rng.uniform(-50.0, 50.0, (600, 3))
    pts[rng.random((600, 3)) < 0.2] = 0.0
    for k in range(len(pts) - 1):
        seg = _line(pts[k], pts[k + 1])
        got, want = lim.block_limits(seg), _block_limits_before(lim, seg)
        assert [x.hex() for x in got] == [x.hex() for x in want]
