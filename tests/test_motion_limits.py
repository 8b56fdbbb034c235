"""Every cycle of the setpoint stream stays inside each axis' velocity, acceleration and jerk
limits (finite differences of the per-cycle positions, tiny float tolerance only)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nc.motion.offline import run
from nc.motion.profile import solve_position
from tests.motion_helpers import arc, check, circle_chords, jagged_polyline, lines, mill_cfg, worst_ratio

def test_corners_and_reversals_end_exactly():
    pts = [(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0), (0, 0, 0), (20, 5, 0), (0, 0, 0), (10, 0, 0), (0, 0, 0)]
    st = check(lines(pts, 3000), mill_cfg())
    assert np.allclose(st.positions[-1], 0.0, atol=1e-9)
    # every corner of the square is visited (the path is followed, not cut)
    for p in pts:
        assert np.min(np.linalg.norm(st.positions - np.array(p, float), axis=1)) < 1e-4


def test_arcs_lines_and_full_circle():
    moves = [lines([(0, 0, 0), (10, 0, 0)], 3000)[0], arc((10, 0, 0), (20, 10, 0), (10, 10), "ccw", 3000),
             arc((20, 10, 0), (30, 20, 0), (30, 10), "cw", 3000), lines([(20, 10, 0), (30, 40, 0)], 3000)[0],
             arc((30, 40, 0), (30, 40, 0), (30, 30), "cw", 3000, line=9)]
    moves[3].start = {"X": 30.0, "Y": 20.0, "Z": 0.0}
    st = check(moves, mill_cfg())
    assert np.allclose(st.positions[-1], [30, 40, 0], atol=1e-9)
    # the full circle keeps its radius on every cycle
    idx = st.lines == 9
    r = np.hypot(st.positions[idx, 0] - 30, st.positions[idx, 1] - 30)
    assert np.all(np.abs(r[r > 1] - 10.0) < 1e-6)


def test_tiny_cam_segments_on_a_smooth_curve():
    rng = np.random.default_rng(5)
    s = np.cumsum(rng.uniform(0.01, 0.1, 1500))
    pts = [(0.0, 0.0, 0.0)] + [(x, 3.0 * math.sin(x / 4.0), 0.2 * math.cos(x / 3.0) - 0.2) for x in s]
    check(lines(pts, 3000), mill_cfg())


def test_jagged_cam_segments_and_z_moves():
    pts = jagged_polyline()
    check(lines(pts, 6000), mill_cfg())


@pytest.mark.parametrize("independent", [False, True])
def test_rapids(independent):
    cfg = mill_cfg(rapid_independent=independent)
    st = check(lines([(0, 0, 0), (50, 30, -20), (0, 0, 0), (5, 0, 0)], None, kind="rapid"), cfg)
    assert np.allclose(st.positions[-1], [5, 0, 0], atol=1e-9)


def test_chord_circle_within_5_percent_of_feed_limited_time():
    cfg = mill_cfg()
    pts = circle_chords(100.0, 0.05)
    st = check(lines(pts, 3000), cfg, start=pts[0])
    feed_limited = 2 * math.pi * 100.0 / 50.0
    assert st.time < 1.05 * feed_limited


def test_a_profile_that_overshoots_between_phase_boundaries_is_seen():
    """Braking from 19.7 mm/s at -1232 mm/s² into 6.6 mm/s over 0.09 mm cannot be done: ruckig's
    time-optimal answer runs past the target and comes back, with both extremes inside phases
    (a passes zero mid-phase). The planner must see that and brake across the next block instead
    (found at the end of a filtered CAM program, where it stopped dead at 7 mm/s)."""
    pw = solve_position(-0.0139, 19.68, -1232.2, 0.0774, 6.6, 28.27, 2000.0, 100_000.0)
    t = np.linspace(0.0, pw.duration, 20_001)
    s, v, _ = pw.sample(t)
    assert pw.p_max == pytest.approx(s.max(), abs=1e-6) and pw.p_max > 0.0774 + 0.03
    assert pw.v_min() == pytest.approx(v.min(), abs=1e-3) and pw.v_min() < -5.0
    assert pw.p.max() <= 0.0774 + 1e-9  # the phase boundaries alone look fine


def test_filtered_cam_program_ends_within_limits():
    rng = np.random.default_rng(5)
    s = np.cumsum(rng.uniform(0.01, 0.1, 1500))
    pts = [(0.0, 0.0, 0.0)] + [(x, 3.0 * math.sin(x / 4.0), 0.2 * math.cos(x / 3.0) - 0.2) for x in s]
    for ms in (8.0, 16.0):
        cfg = mill_cfg(filter_time=ms / 1000, filter_scurve=ms / 1000, min_segment_cycles=0.25)
        st = run(lines(pts, 3000), cfg, {"X": 0.0, "Y": 0.0, "Z": 0.0})
        assert st.state.value == "finished"
        assert max(worst_ratio(st, cfg).values()) <= 1.0 + 1e-6
        assert np.allclose(st.positions[-1], pts[-1], atol=1e-9)
