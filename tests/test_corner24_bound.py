"""The proved isolated-corner bound against the bench's own filter (session 23, decision motion 73).

nc.motion.deviation.CornerBound bounds how far the NC5 position filter's output (N1.036 + N1.037 moving averages)
leaves the legs of a lone line-line corner crossed at speed v with any acceleration there, the raw profile within
(acc, jerk). Here raw profiles that brake hard through the corner, cross it at zero acceleration or speed up
through it are sampled at 1 ms, run through `PositionFilter`, and their largest distance from the legs is
compared with the bound: never above it, and above what the constant-speed term alone (v·G(0)·sin θ) allows,
so the path term is needed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion.deviation import CornerBound, KernelDeviation
from nc.motion.filter_ramps import polyline_distance
from nc.motion.smoothing import PositionFilter

T = 0.001
N1 = N2 = 16  # the mill bench's 16 ms + 16 ms
ACC, JERK = 3536.0, 353_553.0  # a 90° zig-zag leg's tangential limits, the jerk raised 2× (shares.MAX_FACTOR)


def raw_path(v_c: float, a0: float | None, phase: float, span: float = 0.08) -> np.ndarray:
    """Path position (mm, 0 at the corner) every cycle from −span to span s around the crossing: acceleration a0
    at the crossing, constant before it (going back in time the speed rises by −a0 per second while braking),
    after it turned to zero at the full jerk; a0 None: the crossing is the speed's minimum, the acceleration
    rising from zero at the full jerk on both sides up to ACC. Clipped to non-negative speed."""
    dt = 1e-5
    t = np.arange(-span, span, dt)
    if a0 is None:
        a = np.sign(t) * np.minimum(JERK * np.abs(t), ACC)
    else:
        a = np.where(t < 0.0, a0, np.sign(a0) * np.maximum(abs(a0) - JERK * t, 0.0))
    v = np.empty_like(t)
    i0 = int(np.searchsorted(t, 0.0))
    v[i0:] = v_c + np.cumsum(a[i0:]) * dt
    v[:i0] = v_c - np.cumsum(a[:i0][::-1])[::-1] * dt
    v = np.clip(v, 0.0, None)
    s = np.cumsum(v) * dt
    s -= np.interp(0.0, t, s)
    ts = np.arange(-span + phase, span - 1e-9, T)
    return np.interp(ts, t, s)


def deviation(turn_deg: float, s: np.ndarray) -> float:
    th = math.radians(turn_deg)
    u1, u2 = np.array([1.0, 0.0, 0.0]), np.array([math.cos(th), math.sin(th), 0.0])
    pts = np.where(s[:, None] < 0.0, s[:, None] * u1, s[:, None] * u2)
    f = PositionFilter(N1, N2, pts[0].copy())
    out = f.push_many(pts)
    legs = np.array([s[0] * u1, np.zeros(3), s[-1] * u2])
    return float(polyline_distance(out[N1 + N2:], legs).max())


@pytest.mark.parametrize("turn", [60.0, 90.0, 150.0])
@pytest.mark.parametrize("v_c, a_frac", [(3.0, -1.0), (3.0, 0.0), (3.0, 1.0), (3.0, None), (8.0, -1.0),
                                         (8.0, None), (20.0, -1.0), (20.0, 0.5), (20.0, None)])
def test_the_filtered_corner_stays_within_the_bound(turn, v_c, a_frac):
    cb = CornerBound(KernelDeviation(N1, N2, T))
    am = min(ACC, math.sqrt(2.0 * JERK * v_c))  # faster braking through would stop the raw path before it
    a0 = None if a_frac is None else a_frac * am
    th = math.radians(turn)
    bound = math.sin(th) * ACC * cb.bound(v_c / ACC, JERK / ACC)
    worst = max(deviation(turn, raw_path(v_c, a0, ph)) for ph in (0.0, 0.00025, 0.0005, 0.00075))
    assert worst <= bound * (1.0 + 1e-6)
    if a_frac is None:  # speeding up on both sides: the constant-speed term alone is exceeded
        assert worst > 1.1 * math.sin(th) * v_c * KernelDeviation(N1, N2, T).g0


def test_the_cap_keeps_the_bound_within_the_tolerance_and_grows_past_the_old_one():
    cb = CornerBound(KernelDeviation(N1, N2, T))
    g0 = KernelDeviation(N1, N2, T).g0
    for turn, old in ((90.0, 1.774), (120.0, 1.45), (150.0, 1.30)):
        th = math.radians(turn)
        du_n = 2.0 * math.sin(th / 2.0)
        c = cb.cap(0.02, du_n, ACC, JERK, 2.0, 2.0, 50.0, 50.0)
        assert c > 1.3 * old
        ratio = 2.0 ** (math.ceil(math.log2(JERK / ACC) * 16 - 1e-9) / 16)  # the grid's jerk/acc, rounded up
        assert math.sin(th) * ACC * cb.bound(c / ACC, ratio) <= 0.02
        assert c * g0 * math.sin(th) < 0.02
    # a neighbour within a window's reach: no cap (0.3 mm legs), nor where the foot leaves a short leg
    assert cb.cap(0.02, math.sqrt(2.0), ACC, JERK, 0.3, 0.3, 50.0, 50.0) == 0.0
