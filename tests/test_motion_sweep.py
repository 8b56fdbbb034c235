"""The motion sweep: seeded random programs with an operator at the panel (tests/motion_sweep.py), each run
checked as a drive sees it — velocity, acceleration and jerk within the axis limits on every cycle, no setpoint
going back along the path, the program's end point reached. A fast share of the seeds runs in CI; the wide sweep
with `-m slow`."""

from __future__ import annotations

import pytest

from tests.motion_sweep import make_case, run_case

TOL = 1.0 + 1e-6
BACK = 1e-9  # mm: float noise of the path position, not a step back


def _check(seed: int) -> None:
    case = make_case(seed)
    out = run_case(case)
    worst = max(out.ratios, key=out.ratios.get)
    assert out.ratios[worst] <= TOL, f"{case.describe()}: {worst} {out.ratios[worst]:.3f}x the limit"
    assert out.back <= BACK, f"{case.describe()}: a setpoint {out.back * 1000:.4f} µm back along the path"
    assert out.end_error <= 1e-9, f"{case.describe()}: ends {out.end_error} mm from the program's end"


@pytest.mark.parametrize("seed", range(1, 41))
def test_random_programs_keep_every_cycle_within_the_limits(seed):
    _check(seed)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(41, 601))
def test_random_programs_keep_every_cycle_within_the_limits_wide(seed):
    _check(seed)
