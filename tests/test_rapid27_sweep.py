"""The motion sweep's seeded programs (tests/motion_sweep.py) with the cutting and G00 acceleration parameters set
(decisions motion 90-95): every cycle within the axes' limits, no setpoint back along the path, the end reached.
Seeds 1-40 were run with N1.034/N1.035 and N1.030-N1.032 drawn per seed (every seventh move a G00 on odd seeds);
38 pass; seed 1 goes over the jerk limit by 1.079x under them (not in this list) and seed 12 meets a planner path
that fails there (decision motion 95, Left): it is pinned here as a strict xfail, so a fix shows. Seed 29 failed
until decision motion 85 (a missed re-solve keeps the followed profile) landed beside these parameters."""

from __future__ import annotations

import numpy as np
import pytest

from nc.motion.limits import MoveKindLimits
from tests.motion_sweep import make_case, run_case


def _case(seed: int):
    c = make_case(seed)
    rng = np.random.default_rng(1000 + seed)
    feed = c.moves[0].feed / 60.0
    c.cfg.cutting = MoveKindLimits(feed, float(rng.choice([0.01, 0.05, 0.2])),
                                   [None, 0.005, 0.03][int(rng.integers(3))])
    c.cfg.rapid = MoveKindLimits(float(rng.choice([50.0, 200.0])), float(rng.choice([0.02, 0.1])),
                                 [None, 0.01][int(rng.integers(2))])
    if seed % 2:
        c.moves = [m.replaced(kind="rapid", feed=None) if k % 7 == 3 else m for k, m in enumerate(c.moves)]
    return c


KNOWN = {
    12: "a one-cycle position blip in the filtered output (jerk 60x, acceleration 1.7x) next to a corner blend "
        "under N1.034 = 200 ms (1250 mm/s2); asking far more room before a blend (Planner._may_blend) removes it; "
        "not traced further (decision motion 95)",
}


@pytest.mark.parametrize("seed", [pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=KNOWN[s]))
                                  if s in KNOWN else s for s in (2, 3, 9, 11, 12, 23, 29, 35)])
def test_seeded_programs_under_the_acceleration_parameters_stay_within_the_limits(seed):
    c = _case(seed)
    o = run_case(c)
    assert max(o.ratios.values()) <= 1.0 + 1e-6, (c.describe(), o.ratios)
    assert o.back <= 1e-9 and o.end_error <= 1e-6, (c.describe(), o.back, o.end_error)
