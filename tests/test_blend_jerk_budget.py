"""Decision motion 47: a corner blend's cap, tangential acceleration and tangential jerk keep every axis
within its limits at any point of the blend, for any a_t and j_t the planner may use there (either sign),
at any speed up to the cap. The jerk there is (j_t − v³κ²)·t + (v³·dκ/ds + 3·v·a_t·κ)·n: read off the
blend's own geometry (its heading turning in the plane of u1, n1; κ rising linearly to κmax and back)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion import AxisLimits, MotionConfig
from nc.motion.clothoid import corner_blend
from nc.motion.lookahead import Limits
from tests.test_blend_segment import _line

LIM = {"X": AxisLimits(500, 5000, 250_000), "Y": AxisLimits(500, 5000, 250_000), "Z": AxisLimits(300, 3000, 150_000)}
AXES = ("X", "Y", "Z")


def _worst(seg, v: float, a: float, j: float) -> tuple[np.ndarray, np.ndarray]:
    """Largest |acceleration| and |jerk| per axis over the blend at speed v, a_t = ±a, j_t = ±j."""
    s = np.linspace(0.0, seg.length, 2001)
    L, th = seg.half, seg.turn
    kap = np.where(s <= L, s, seg.length - s) * th / (L * L)  # triangle: 0 → θ/L → 0
    dk = np.where(s <= L, 1.0, -1.0) * th / (L * L)
    phi = np.where(s <= L, 0.5 * kap * s, th - 0.5 * kap * (seg.length - s))  # heading from u1
    t = np.cos(phi)[:, None] * seg.u1 + np.sin(phi)[:, None] * seg.n1
    n = -np.sin(phi)[:, None] * seg.u1 + np.cos(phi)[:, None] * seg.n1
    acc = jerk = np.zeros(3)
    for sa in (-1.0, 1.0):
        for sj in (-1.0, 1.0):
            A = sa * a * t + (v * v * kap)[:, None] * n
            J = (sj * j - v ** 3 * kap * kap)[:, None] * t + (v ** 3 * dk + 3.0 * v * sa * a * kap)[:, None] * n
            acc = np.maximum(acc, np.abs(A).max(axis=0))
            jerk = np.maximum(jerk, np.abs(J).max(axis=0))
    return acc, jerk


@pytest.mark.parametrize("seed", range(6))
def test_a_blend_planned_at_its_limits_keeps_every_axis_within_its_own(seed):
    rng = np.random.default_rng(seed)
    lim = Limits(MotionConfig(axes=AXES, limits=LIM, path_tolerance=0.02))
    amax = np.array([LIM[x].max_acceleration for x in AXES])
    jmax = np.array([LIM[x].max_jerk for x in AXES])
    worst = 0.0
    for _ in range(40):
        u1 = rng.normal(size=3)
        u2 = rng.normal(size=3) * [1.0, 1.0, rng.uniform(0.0, 2.0)]
        u1, u2 = u1 / np.linalg.norm(u1), u2 / np.linalg.norm(u2)
        if u1 @ u2 < math.cos(math.radians(130.0)):
            continue
        l1, l2 = rng.uniform(0.2, 4.0, 2)
        vx = np.array([1.0, 2.0, 3.0])
        s1, s2 = _line(vx - l1 * u1, vx), _line(vx, vx + l2 * u2)
        seg = corner_blend(s1, s2, 0.02, l1, l2)
        if seg is None:
            continue
        v, a, j = lim.block_limits(seg)
        assert v > 0.0 and a > 0.0 and j > 0.0
        for f in (1.0, 0.7, 0.3):  # below the cap a_t and j_t keep their room
            acc, jerk = _worst(seg, f * v, a, j)
            assert np.all(acc <= amax * (1.0 + 1e-9)), (acc / amax, seg.turn)
            assert np.all(jerk <= jmax * (1.0 + 1e-9)), (jerk / jmax, seg.turn)
            worst = max(worst, float(np.max(jerk / jmax)))
    assert worst > 0.85  # the budget is used, not left idle (the sum of decisions 42/46 used ≤ 0.8 + 0.2)
