"""What an isolated corner costs under the NC5 position filter, by its geometry (session 22, decision motion 72).

The filter (N1.036 + N1.037, two moving averages) outputs C − u1·m1 + u2·m2 near a lone corner C between
directions u1 and u2 (m1, m2 ≥ 0 the kernel-weighted path before and after C), whose distance from the
programmed legs is min(m1, m2)·sin θ. The isolated-corner cap (FilterCorners.corner_tolerance) charges the
constant-speed part v·G(0)·|Δu| instead, |Δu| = 2·sin(θ/2): 1/cos(θ/2) more than the geometry needs
(1.41× at 90°, 2× at 120°, 3.9× at 150°). Decision 72 records this as the bound looser than its proof, left
unchanged this session; this test pins the geometry it rests on with the bench's own filter.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion.deviation import KernelDeviation
from nc.motion.filter_ramps import polyline_distance
from nc.motion.smoothing import PositionFilter

T = 0.001
N1 = N2 = 16  # N1.036 = N1.037 = 16 ms on the mill bench


def corner_deviation(turn_deg: float, v: float) -> float:
    """Largest distance of the filtered output from the two legs, a corner crossed at constant speed v."""
    th = math.radians(turn_deg)
    u1 = np.array([1.0, 0.0, 0.0])
    u2 = np.array([math.cos(th), math.sin(th), 0.0])
    leg = 2.0  # mm, as the LinuxCNC family's lines
    n = int(round(leg / (v * T)))
    s = v * T * np.arange(-n, n + 1)
    raw = np.where(s[:, None] < 0.0, s[:, None] * u1, s[:, None] * u2)
    f = PositionFilter(N1, N2, raw[0].copy())
    out = f.push_many(raw)
    pts = np.array([leg * -u1, np.zeros(3), leg * u2])
    return float(polyline_distance(out[N1 + N2:], pts).max())


@pytest.mark.parametrize("turn", [60.0, 90.0, 120.0, 150.0])
def test_constant_speed_corner_deviation_is_sin_theta_times_the_kernel_moment(turn):
    g0 = KernelDeviation(N1, N2, T).g0
    v = 20.0  # mm/s: the window (31 cycles, 0.62 mm) holds one corner only
    d = corner_deviation(turn, v)
    th = math.radians(turn)
    du_n = 2.0 * math.sin(th / 2.0)
    # the geometry: v·G(0)·sin θ, within the discrete kernel's rounding
    assert d == pytest.approx(v * g0 * math.sin(th), rel=0.02)
    # what the isolated-corner cap charges for the same crossing: 1/cos(θ/2) more
    assert v * g0 * du_n / d == pytest.approx(1.0 / math.cos(th / 2.0), rel=0.02)
