"""A path solve's ruckig plumbing (nc.motion.profile, decision bench B154): the pooled 1-DoF input written only where
a field's double changed, one Trajectory refilled by every calculate, and a repeat of the last solve's inputs
answered without ruckig. Each solve must still give the profile a fresh calculator, input and trajectory give for
the same inputs, bit for bit, whatever was solved before it (velocity ramps and independent-axis solves share the
pool; a retry after ruckig throws writes the input itself)."""

from __future__ import annotations

import math
import random

from ruckig import ControlInterface, InputParameter, Result, Ruckig, Synchronization, Trajectory

from nc.motion import profile
from nc.motion.profile import solve_axes, solve_position, solve_velocity


def _fresh(p0: float, v0: float, a0: float, p1: float, v1: float, v_max: float, a_max: float,
           j_max: float) -> tuple | None:
    """The reference: (duration, p_max, phases) of a new Ruckig, InputParameter and Trajectory for the solve,
    as solve_position asks it (its v_max held to 1e-9; ruckig's throw retried as `_calculate` retries)."""
    otg, inp = Ruckig(1), InputParameter(1)
    inp.control_interface = ControlInterface.Position
    inp.synchronization = Synchronization.Time
    inp.current_position, inp.current_velocity, inp.current_acceleration = [p0], [v0], [a0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [p1], [v1], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [max(v_max, 1e-9)], [a_max], [j_max]
    a = [a0 * (1.0 - 1e-12)]
    for acc, jerk in (([a0], [j_max]), (a, [j_max]), (a, [j_max * (1.0 - 1e-9)])):
        inp.current_acceleration, inp.max_jerk = acc, jerk
        traj = Trajectory(1)
        try:
            res = otg.calculate(inp, traj)
        except Exception:  # ruckig.RuckigError: the next retry
            continue
        if res not in (Result.Working, Result.Finished):
            return None
        pw = profile.Piecewise.of(traj)
        return pw.duration, pw.p_max, pw._lists
    return None


def _answer(pw) -> tuple | None:
    return None if pw is None else (pw.duration, pw.p_max, pw._lists)


def _same_bits(x, y) -> bool:
    """Equal as the doubles' bits (repr tells −0.0 from 0.0, and every float apart)."""
    return repr(x) == repr(y)


def _states(seed: int, n: int) -> list[tuple[float, ...]]:
    """Solves as a planner makes them: most inputs kept from the solve before, one to three changed, zeros (both
    signs) and exact repeats among them."""
    rng = random.Random(seed)
    cur = [0.0, 0.0, 0.0, 5.0, 0.0, 50.0, 1500.0, 75000.0]
    out = []
    for _ in range(n):
        r = rng.random()
        if r < 0.15:
            out.append(tuple(cur))  # the same solve again
            continue
        for k in rng.sample(range(8), rng.randint(1, 3)):
            if k == 0:
                cur[0] = rng.choice([0.0, -0.0, rng.uniform(0.0, 4.0)])
            elif k == 1:
                cur[1] = rng.choice([0.0, -0.0, rng.uniform(0.0, 60.0)])
            elif k == 2:
                cur[2] = rng.choice([0.0, -0.0, rng.uniform(-1500.0, 1500.0)])
            elif k == 3:
                cur[3] = cur[0] + rng.uniform(0.001, 10.0)
            elif k == 4:
                cur[4] = rng.choice([0.0, -0.0, rng.uniform(0.0, 40.0)])
            elif k == 5:
                cur[5] = rng.choice([0.0, rng.uniform(1.0, 60.0)])
            elif k == 6:
                cur[6] = rng.choice([1500.0, 750.0, rng.uniform(100.0, 3000.0)])
            else:
                cur[7] = rng.choice([75000.0, 150000.0, rng.uniform(1e4, 2e5)])
        out.append(tuple(cur))
    return out


def test_pooled_solves_match_fresh_ruckig_bit_for_bit() -> None:
    rng = random.Random(7)
    n = 0
    for args in _states(28, 600):
        # other solves between path solves share the pool (a one-axis rapid shares the 1-DoF input)
        if rng.random() < 0.1:
            solve_velocity(0.0, rng.uniform(0.0, 50.0), 0.0, 0.0, 1500.0, 75000.0)
        if rng.random() < 0.05:
            solve_axes([0.0], [0.0], [0.0], [rng.uniform(0.1, 5.0)], [100.0], [2000.0], [1e5])
        got, want = _answer(solve_position(*args)), _fresh(*args)
        assert (got is None) == (want is None), args
        if want is not None:
            assert _same_bits(got, want), args
            n += 1
    assert n > 300  # (the rest: ruckig has no profile, a zero top speed among them)


def test_retry_at_a_phase_boundary_then_the_next_solve() -> None:
    # ruckig 0.19 throws on 0 → 1.2 + 1 ulp at a 1500, j 75000; `_calculate` retries with the acceleration and
    # jerk it writes itself: the solve after it (same limits) must not keep those written values
    edge = (0.0, 0.0, 0.0, 1.2 + 2.220446049250313e-16, 0.0, 50.0, 1500.0, 75000.0)
    after = (0.1, 3.0, 200.0, 1.2 + 2.220446049250313e-16, 0.0, 50.0, 1500.0, 75000.0)
    for args in (edge, after, edge, edge, after):
        assert _same_bits(_answer(solve_position(*args)), _fresh(*args)), args


def test_repeated_path_solve_does_not_call_ruckig_again() -> None:
    solve_position(0.0, 0.0, 0.0, 1.0, 0.0, 10.0, 1500.0, 75000.0)
    if 1 not in profile._POOL:  # made by the first solve where ruckig's Python module solves, not ruckig_direct
        profile._POOL[1] = (Ruckig(1), InputParameter(1))
    otg, inp = profile._POOL[1]  # the pooled 1-DoF calculator

    class Counting:
        calls = 0

        def calculate(self, i: InputParameter, t: Trajectory) -> Result:
            Counting.calls += 1
            return otg.calculate(i, t)

    profile._POOL[1] = (Counting(), inp)
    direct = profile._DIRECT  # ruckig's C++ called directly where built (decision bench B162): count its solves
    if direct is not None:
        def counting(*args: object) -> object:
            Counting.calls += 1
            return direct(*args)
        profile._DIRECT = counting
    try:
        args = (0.25, 12.0, -300.0, 4.75, 6.0, 40.0, 1500.0, 75000.0)
        first = solve_position(*args)
        n = Counting.calls
        again = solve_position(*args)
        assert Counting.calls == n  # answered without ruckig
        assert again is not None and _same_bits(_answer(again), _fresh(*args))
        assert again.v_min() == first.v_min() and again.at(0.01) == first.at(0.01)
        # one input one ulp off, or a zero of the other sign, is a new solve
        for k, x in ((3, math.nextafter(4.75, 5.0)), (4, 0.0), (4, -0.0)):
            other = list(args)
            other[k] = x
            before = Counting.calls
            assert _same_bits(_answer(solve_position(*other)), _fresh(*other))
            assert Counting.calls == before + 1
    finally:
        profile._POOL[1] = (otg, inp)
        profile._DIRECT = direct
