"""Two corners close together under the position filter, with a short block between them that the profile speeds up
on (decision motion 82): the filter windows are crossed faster than the junctions, so more of the path falls in one
window than the junctions' own speed says. Found by the motion sweep (tests/test_motion_sweep.py, seed 167)."""

from __future__ import annotations

import numpy as np
import pytest

from nc.motion.offline import run
from tests.motion_helpers import AX, TOL, lines, mill_cfg, worst_ratio

# a zig-zag: 2 mm, 0.5 mm back at about 130°, 2 mm on again (three lines of the sweep's seed 167)
ZIGZAG = [(0.0, 0.0, 0.0), (0.083, -1.9832, 0.2452), (-0.1437, -1.576, 0.4263), (-0.1284, -3.5662, 0.2291)]


@pytest.mark.parametrize("feed", [3000.0, 15000.0])
def test_two_close_corners_without_a_path_tolerance_keep_the_jerk(feed):
    """N1.053 = 0 (no tolerance: the corners are held by the filter's budgets alone), 16 ms + 16 ms. The profile
    speeds up from 14.1 to 16.7 mm/s on the 0.5 mm block, so the two corners are 27 ms apart, not the 35 ms the
    junction speed gives: both velocity steps fell in the two halves of one T1 + T2 window, Y's jerk 1.207x the
    limit. Now within it, and the program takes no more than a tenth longer (0.214 -> 0.233 s)."""
    cfg = mill_cfg(filter_time=0.016, filter_scurve=0.016, path_tolerance=None, min_segment_cycles=0.25)
    st = run(lines(ZIGZAG, feed), cfg, dict(zip(AX, (0.0, 0.0, 0.0))))
    assert st.state.value == "finished" and not st.alarms
    r = worst_ratio(st, cfg)
    assert r["j"] <= TOL and r["a"] <= TOL and r["v"] <= TOL, r
    assert np.allclose(st.positions[-1], ZIGZAG[-1], atol=1e-9)
    assert 0.214 <= st.time <= 0.236, st.time
