"""Operator controls: override mid-motion, feed hold/resume mid-segment, reset, single block, dry run,
exact stop — all within the axis limits on every cycle."""

from __future__ import annotations

import numpy as np

from nc.channel import RunState
from nc.motion.offline import run
from tests.motion_helpers import AX, lines, mill_cfg, single_block_operator, worst_ratio

TOL = 1.0 + 1e-6


def _speed(st):
    return np.linalg.norm(np.diff(st.positions, axis=0), axis=1) / st.cycle


def test_feed_override_changes_mid_motion_within_limits():
    cfg = mill_cfg()
    def ctl(n, ch):
        if n == 300:
            ch.feed_override = 1.5
        if n == 900:
            ch.feed_override = 0.2
    st = run(lines([(0, 0, 0), (100, 0, 0)], 1200), cfg, dict(zip(AX, (0, 0, 0))), on_cycle=ctl)
    v = _speed(st)
    assert abs(v[800] - 30.0) < 1e-6  # 150 % of F1200 (20 mm/s)
    assert abs(v[1300] - 4.0) < 1e-6  # 20 %
    r = worst_ratio(st, cfg)
    assert max(r.values()) <= TOL
    assert np.allclose(st.positions[-1], [100, 0, 0], atol=1e-9)


def test_feed_hold_stops_mid_segment_and_resume_finishes():
    cfg = mill_cfg()
    held = {}
    def ctl(n, ch):
        if n == 200:
            ch.feed_hold()
        if n == 700:
            held["pos"] = ch.planner.position.copy()
            held["state"] = ch.state
            ch.cycle_start()
    st = run(lines([(0, 0, 0), (50, 0, 0), (50, 20, 0)], 3000), cfg, dict(zip(AX, (0, 0, 0))), on_cycle=ctl)
    assert held["state"] is RunState.HOLD
    assert 5.0 < held["pos"][0] < 50.0 and held["pos"][1] == 0.0  # stopped inside the first segment
    assert np.all(_speed(st)[600:699] == 0.0)
    assert st.state is RunState.FINISHED and np.allclose(st.positions[-1], [50, 20, 0], atol=1e-9)
    assert max(worst_ratio(st, cfg).values()) <= TOL


def test_reset_is_a_controlled_stop_then_flush():
    cfg = mill_cfg()
    def ctl(n, ch):
        if n == 150:
            ch.reset()
    st = run(lines([(0, 0, 0), (80, 0, 0), (80, 80, 0)], 6000), cfg, dict(zip(AX, (0, 0, 0))), on_cycle=ctl)
    assert st.state is RunState.IDLE
    assert st.positions[-1][0] < 80.0 and st.positions[-1][1] == 0.0
    assert max(worst_ratio(st, cfg).values()) <= TOL


def test_single_block_stops_after_each_block():
    cfg = mill_cfg()
    stops: list = []
    st = run(lines([(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0)], 3000), cfg, dict(zip(AX, (0, 0, 0))),
             on_cycle=single_block_operator(stops))
    assert [tuple(np.round(p, 6)) for p in stops] == [(10, 0, 0), (10, 10, 0), (0, 10, 0)]
    assert st.state is RunState.FINISHED


def test_dry_run_uses_dry_run_feed():
    cfg = mill_cfg()
    def ctl(n, ch):
        if n == 0:
            ch.dry_run_feed = 2400.0
            ch.dry_run = True
    st = run(lines([(0, 0, 0), (100, 0, 0)], 60), cfg, dict(zip(AX, (0, 0, 0))), on_cycle=ctl)
    assert abs(_speed(st).max() - 40.0) < 1e-6


def test_exact_stop_reaches_rest_at_the_block_end():
    cfg = mill_cfg()
    mv = lines([(0, 0, 0), (10, 0, 0), (20, 0.5, 0)], 3000)
    mv = lines([(0, 0, 0), (10, 0, 0), (20, 0.5, 0)], 3000)
    mv[0].exact_stop = True
    st_g09 = run(mv, cfg, dict(zip(AX, (0, 0, 0))))
    k = int(np.argmin(np.linalg.norm(st_g09.positions - [10, 0, 0], axis=1)))
    assert np.allclose(st_g09.positions[k], [10, 0, 0], atol=1e-4)
    assert max(_speed(st_g09)[k - 1], _speed(st_g09)[k]) < 0.05  # at rest on the corner (mm/s)


def test_slow_rapid_at_zero_rapid_override():
    cfg = mill_cfg(slow_rapid=5.0)
    def ctl(n, ch):
        if n == 0:
            ch.rapid_override = 0.0
    st = run(lines([(0, 0, 0), (20, 0, 0)], None, kind="rapid"), cfg, dict(zip(AX, (0, 0, 0))), on_cycle=ctl)
    assert abs(_speed(st).max() - 5.0) < 1e-6


def test_lookahead_depth_rule():
    assert mill_cfg().lookahead_depth() == 100
    from nc.motion import AxisLimits, MotionConfig
    cfg = MotionConfig(axes=("X",), limits={"X": AxisLimits(1000.0, 1000.0, 1e6)}, cycle=0.001)
    assert cfg.lookahead_depth() == 500
    assert MotionConfig(lookahead=20).lookahead_depth() == 20
