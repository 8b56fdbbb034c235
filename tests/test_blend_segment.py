"""nc.motion.clothoid: the corner blend as a path segment (decision motion 41), read off its own points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion.clothoid import MAX_TURN, clothoid_pair, corner_blend
from nc.motion.path import Segment
from nc.moves import Move

AXES = ("X", "Y", "Z")


def _line(p, q) -> Segment:
    p, q = dict(zip(AXES, map(float, p))), dict(zip(AXES, map(float, q)))
    return Segment.of(Move("line", 1, "G01", p, q, q, feed=1000.0), AXES)


def _corner(theta: float, len1: float = 5.0, len2: float = 5.0, tilt: float = 0.3):
    """Two lines meeting at (1, 2, 3), turning by theta in a plane tilted out of XY."""
    vx = np.array([1.0, 2.0, 3.0])
    u1 = np.array([1.0, 0.0, 0.0])
    u2 = np.array([math.cos(theta), math.sin(theta) * math.cos(tilt), math.sin(theta) * math.sin(tilt)])
    return _line(vx - len1 * u1, vx), _line(vx, vx + len2 * u2), vx, u1, u2


@pytest.mark.parametrize("deg", [2.0, 15.0, 90.0, 130.0])
def test_the_blend_joins_both_lines_tangent_and_turns_as_a_clothoid_pair(deg):
    theta = math.radians(deg)
    s1, s2, vx, u1, u2 = _corner(theta)
    b = corner_blend(s1, s2, 0.02, s1.length, s2.length)
    assert b is not None and b.kind == "blend"
    # it starts and ends on the lines, tlen from the corner, with their headings
    assert np.allclose(b.points(np.array([0.0]))[0], vx - b.tlen * u1, atol=1e-12)
    assert np.allclose(b.points(np.array([b.length]))[0], vx + b.tlen * u2, atol=1e-12)
    ds = b.length / 20_000
    s = np.arange(20_001) * ds
    q = b.points(s)
    step = np.linalg.norm(np.diff(q, axis=0), axis=1)
    assert step == pytest.approx(ds, rel=1e-4)  # parametrised by path length
    t = np.diff(q, axis=0) / step[:, None]
    assert np.allclose(t[0], u1, atol=1e-3) and np.allclose(t[-1], u2, atol=1e-3)
    assert np.allclose(b.unit_tangent(False), u1) and np.allclose(b.unit_tangent(True), u2)
    # curvature: linear up to θ/L at the middle and back, zero at both ends
    k = np.linalg.norm(np.diff(t, axis=0), axis=1) / ds
    assert k.max() == pytest.approx(b.kappa_max, rel=2e-3)
    assert k[0] < 1e-3 * b.kappa_max + 1e-9 and k[-1] < 1e-3 * b.kappa_max + 1e-9
    mid = len(k) // 4
    assert k[mid] == pytest.approx(b.dkappa * s[mid + 1], rel=2e-3)
    # within the tolerance of the corner: distance to the nearer leg
    d1 = np.linalg.norm(np.cross(q - vx, u1), axis=1)
    d2 = np.linalg.norm(np.cross(q - vx, u2), axis=1)
    dev = float(np.max(np.minimum(d1, d2)))
    assert dev == pytest.approx(b.deviation, rel=1e-3) and dev <= 0.02 * (1 + 1e-9)
    # the direction cosines bound every axis' share of the heading, and are reached
    assert np.all(np.abs(t).max(axis=0) <= b.max_direction_cosines() + 1e-9)
    assert np.abs(t).max(axis=0) == pytest.approx(b.max_direction_cosines(), abs=1e-3)


def test_short_lines_bound_the_blend_to_half_of_either():
    s1, s2, *_ = _corner(math.radians(15.0), len1=0.6, len2=0.9)
    b = corner_blend(s1, s2, 0.02, 0.6, 0.9)
    assert b.tlen == pytest.approx(0.3)
    assert b.deviation < 0.02  # the half rule bound it, not the tolerance
    s1, s2, *_ = _corner(math.radians(15.0), len1=50.0, len2=50.0)
    b = corner_blend(s1, s2, 0.02, 50.0, 50.0)
    assert b.deviation == pytest.approx(0.02) and b.tlen < 1.0
    assert b.tlen == pytest.approx(clothoid_pair(b.turn)[0] * b.half)


def test_tangent_and_sharp_junctions_get_no_blend():
    s1, s2, *_ = _corner(0.0)
    assert corner_blend(s1, s2, 0.02, 5.0, 5.0) is None
    s1, s2, *_ = _corner(MAX_TURN + 0.01)
    assert corner_blend(s1, s2, 0.02, 5.0, 5.0) is None
    s1, s2, *_ = _corner(0.5)
    assert corner_blend(s1, s2, 0.0, 5.0, 5.0) is None
