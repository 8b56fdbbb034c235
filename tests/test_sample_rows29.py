"""Piecewise.at's steps as C functions (nc.motion.profile `_lists0`, `_pos_at`, `_row_at`; decision bench B169):
sample_rows' bisection probes and kept rows read the same floats `Piecewise.sample` gives, bit for bit, on random
1-DoF solves (brake pre-phases included), times before the start and past the end clamped, and after the ramp
fallback stretches the duration (the lists remade from the arrays)."""

from __future__ import annotations

import numpy as np
from ruckig import ControlInterface

from nc.motion.profile import Piecewise, _lists0, _pos_at, _row_at
from tests.test_solve27_phases import _solve, _states


def _bits(x: float) -> int:
    return int(np.float64(x).view(np.int64))


def test_probes_and_rows_are_sample_s_floats():
    rng = np.random.default_rng(29)
    solved = 0
    for interface in (ControlInterface.Position, ControlInterface.Velocity):
        for state in _states(rng, 150):
            traj = _solve(interface, state)
            if traj is None:
                continue
            solved += 1
            pw = Piecewise.of(traj)
            base = float(rng.uniform(-3.0, 3.0))
            for stretch in (1.0, 0.5):
                if stretch != 1.0:  # the ramp fallback's shorter duration: `_lists0` remakes the lists
                    pw.duration = stretch * pw.duration
                c = _lists0(pw)
                assert c[0] == pw.duration and pw._lists is c
                for t in np.linspace(-0.01, pw.duration + 0.01, 9):
                    s, v, a = pw.sample(np.array([t]))
                    want = (float(s[0] - base), float(v[0]), float(a[0]))
                    got = _row_at(float(t), base, *c)
                    assert [_bits(x) for x in got] == [_bits(x) for x in want], (state, t)
                    assert _bits(_pos_at(float(t), *c) - base) == _bits(want[0]), (state, t)
                    assert pw.at(float(t)) == (float(s[0]), float(v[0]), float(a[0])), (state, t)
    assert solved > 250, solved
