"""The motion sweep (decision motion 81): seeded random programs with an operator at the panel
(tests/motion_sweep.py), each run checked as a drive sees it — velocity, acceleration and jerk within the axis limits
on every cycle, no setpoint going back along the path, the program's end point reached. Seeds 1–40 and the seeds that
found a bug since fixed run in CI; 41–600 with `-m slow`.

KNOWN: the seeds still over a limit, each with what takes it there. They are `xfail(strict=True)`: a fix that makes
one pass fails the run until its entry is taken off, so the table only ever shrinks with the bugs."""

from __future__ import annotations

import pytest

from tests.motion_sweep import make_case, run_case

TOL = 1.0 + 1e-6
BACK = 1e-9  # mm: float noise of the path position, not a step back
# found a bug, fixed since: 167 (decision motion 82); 96, 220, 226, 294, 469, 360 (motion 83); 1, 498 (motion 84)
FIXED = [96, 167, 220, 226, 294, 360, 469, 498]  # (seeds 1–40 run in CI anyway)
# (empty since decisions motion 83 (c) and 84, session 26: seeds 1, 15, 96, 220, 226, 294, 360, 469, 498 were here)
KNOWN: dict[int, str] = {}


def _check(seed: int) -> None:
    case = make_case(seed)
    out = run_case(case)
    worst = max(out.ratios, key=out.ratios.get)
    assert out.ratios[worst] <= TOL, f"{case.describe()}: {worst} {out.ratios[worst]:.3f}x the limit"
    assert out.back <= BACK, f"{case.describe()}: a setpoint {out.back * 1000:.4f} µm back along the path"
    assert out.end_error <= 1e-9, f"{case.describe()}: ends {out.end_error} mm from the program's end"


def _seeds(seeds) -> list:
    return [pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=KNOWN[s])) if s in KNOWN else s
            for s in seeds]


@pytest.mark.parametrize("seed", _seeds(list(range(1, 41)) + FIXED))
def test_random_programs_keep_every_cycle_within_the_limits(seed):
    _check(seed)


@pytest.mark.slow
@pytest.mark.parametrize("seed", _seeds([s for s in range(41, 601) if s not in FIXED]))
def test_random_programs_keep_every_cycle_within_the_limits_wide(seed):
    _check(seed)
