"""The planner's samples a stretch at a time (nc/motion/stretch.py, issue 17) equal step() cycle by cycle: the
same setpoints, lines and speeds bit for bit, and the planner left in the same state, with and without the
position filter, across holds and resumes."""

from __future__ import annotations

import numpy as np
import pytest

from nc.motion.planner import Planner
from nc.motion.stretch import sample_stretch, settle_stretch, stand_stretch
from tests.motion_helpers import AX, lines, mill_cfg


def _planner(cfg, rpms: list[float], at: list[int]) -> Planner:
    return Planner(cfg, dict(zip(AX, (0.0, 0.0, 0.0))), spindle_rpm=lambda: rpms[at[0]],
                   spindle_angle=lambda: 0.0, spindle_command=lambda: 1000.0)


def _state(pl: Planner) -> tuple:
    return (pl.position.tolist(), pl.line, pl.s, pl.v, pl.a, pl._buf_i, pl._settle.cycles, pl.output.tolist(),
            pl.filter.output.tolist() if pl.filter is not None else None, len(pl.blocks), pl._carry, pl._started)


@pytest.mark.parametrize("filter_ms", [0.0, 16.0])
@pytest.mark.parametrize("seed", range(3))
def test_sample_stretch_equals_step_cycle_by_cycle(filter_ms, seed):
    rng = np.random.default_rng(seed)
    pts = np.cumsum(rng.uniform(-8, 12, (25, 3)) * [1, 1, 0.2], axis=0)
    moves = lines([(0.0, 0.0, 0.0), *map(tuple, pts)], float(rng.uniform(1500, 6000)))
    cfg = mill_cfg(filter_time=filter_ms / 1000.0, filter_scurve=filter_ms / 1000.0) if filter_ms else mill_cfg()
    rpms = list(1000.0 + rng.normal(0, 0.5, 20_000) * (rng.random(20_000) < 0.3))
    hold_at, resume_at = int(rng.integers(300, 900)), int(rng.integers(1000, 1500))
    one_at, many_at = [0], [0]
    one, many = _planner(cfg, rpms, one_at), _planner(cfg, rpms, many_at)
    for pl in (one, many):
        for mv in moves:
            pl.push(mv)

    def events(pl: Planner, k: int) -> None:
        if k == hold_at:
            pl.hold()
        if k == resume_at:
            pl.resume()

    want, states = [], []
    for k in range(len(rpms)):
        one_at[0] = k
        events(one, k)
        sp = one.step()
        want.append((sp.positions.tolist(), sp.line, sp.path_velocity, sp.move.line if sp.move else None))
        states.append(_state(one))
        if one.idle and k > resume_at:
            break
    got, k, stretched = [], 0, 0
    while k < len(want):
        events(many, k)
        c = min(int(rng.integers(1, 80)), len(want) - k)
        for stop in (hold_at, resume_at):  # an operator event is a cycle the stretch ends before
            if k < stop < k + c:
                c = stop - k
        s = sample_stretch(many, c)
        if s is None and k > resume_at:  # the path's end: the filter's tail with the planner standing
            s = stand_stretch(many, c)
        if s is None:
            many_at[0] = k
            sp = many.step()
            got.append((sp.positions.tolist(), sp.line, sp.path_velocity, sp.move.line if sp.move else None))
            k += 1
        else:
            m = len(s.lines)
            settle_stretch(many, rpms[k:k + m], [1000.0] * m)
            got += [(row, line, float(v), s.move.line if s.move else None)
                    for row, line, v in zip(s.positions.tolist(), s.lines, s.path_velocity)]
            k, stretched = k + m, stretched + m
        assert _state(many) == states[k - 1], f"cycle {k - 1}"
    assert got == want
    assert stretched > len(want) // 2  # most cycles went in stretches
