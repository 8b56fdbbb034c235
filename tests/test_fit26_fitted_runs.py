"""The motion sweep's seeds over a limit that decision motion 83 fixed, each cut to the shortest start of its
program that still went over a limit or stepped back along the path before the fix: the sweep's program for the
seed (tests/motion_sweep.py, its operator included), its first k moves, run to their end. A drive must see every
cycle within the axes' velocity, acceleration and jerk and no setpoint going back along the path."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.motion_helpers import AX
from tests.motion_sweep import Case, make_case, run_case

TOL = 1.0 + 1e-6
BACK = 1e-9  # mm: float noise of the path position


def first_moves(seed: int, k: int) -> Case:
    c = make_case(seed)
    moves = c.moves[:k]
    return replace(c, moves=moves, end=np.array([moves[-1].end[a] for a in AX]))


def check(case: Case) -> None:
    out = run_case(case)
    worst = max(out.ratios, key=out.ratios.get)
    assert out.ratios[worst] <= TOL, f"{case.describe()}: {worst} {out.ratios[worst]:.3f}x the limit"
    assert out.back <= BACK, f"{case.describe()}: a setpoint {out.back * 1000:.4f} µm back along the path"
    assert out.end_error <= 1e-9, f"{case.describe()}: ends {out.end_error} mm from its end"


@pytest.mark.parametrize("seed, k", [(226, 85), (96, 89), (469, 24)])
def test_a_state_above_the_next_spans_caps_brakes_through_them(seed, k):
    """A plan ends a long span at zero acceleration at the speed the backward pass allows there (braking on
    through the short spans after it to a stop), above the short spans' cap: no run from that state could pass
    their lower cap, the fallback ramp ran into them too fast and on across the stop (before: jerk 11.4x and a
    4.4 µm step back (226), 11.7x (96), 2.29x at a 1.2 µm span chain without the filter (469))."""
    check(first_moves(seed, k))


@pytest.mark.parametrize("seed, k", [(15, 2), (220, 27), (294, 75)])
def test_the_fallback_ramp_cruises_to_its_runs_end_not_past_it(seed, k):
    """A ramp that cannot meet its run's target cruises at the target speed to the run's end: it cruised for
    (dist − s)/target after the ramp as well, past the end into blocks that allow less (before: 0.49 µm back
    along the path on two moves (15), 23 nm back after an override cut to 5 % (220), jerk 1.33x (294)). (15 and
    294 ramp there after a re-solve ruckig missed: decision motion 83, Left.)"""
    check(first_moves(seed, k))

