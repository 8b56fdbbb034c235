"""A solve's phases and lowest speed as plain floats (nc.motion.profile `_phases`, `Piecewise.v_min`; decision bench
B140): the compiled C loops give the floats the list comprehensions before them gave, bit for bit, on random 1-DoF
solves of both interfaces, brake pre-phases (a state above the velocity or acceleration limit) included, and
`at` samples them as `sample` samples the arrays."""

from __future__ import annotations

import numpy as np
from ruckig import ControlInterface, InputParameter, Result, Ruckig, Synchronization, Trajectory

from nc.motion.profile import Piecewise


def _phases_before(pr) -> tuple[list, list, list, list, list]:
    """_phases as it was before B140 (session 12's comprehensions), the reference."""
    t0, p, v, a, j = [], [], [], [], []
    t = 0.0
    b = pr.brake
    if b.duration > 0.0:
        bt, bp, bv, ba, bj = b.t, b.p, b.v, b.a, b.j
        for k in range(2):
            if bt[k] > 0.0:
                t0.append(t), p.append(bp[k]), v.append(bv[k]), a.append(ba[k]), j.append(bj[k])
                t += bt[k]
    pt = pr.t
    ks = [k for k in range(7) if pt[k] > 0.0]
    for k in ks:
        t0.append(t)
        t += pt[k]
    pp, pv, pa, pj = pr.p, pr.v, pr.a, pr.j
    p += [pp[k] for k in ks]
    v += [pv[k] for k in ks]
    a += [pa[k] for k in ks]
    j += [pj[k] for k in ks]
    if t0:
        h = t - t0[-1]
        pl, vl, al, jl = p[-1], v[-1], a[-1], j[-1]
        pe = pl + h * (vl + h * (al / 2.0 + h * jl / 6.0))
        ve = vl + h * (al + h * jl / 2.0)
        ae = al + h * jl
    else:
        pe, ve, ae = pp[0], pv[0], pa[0]
    t0.append(t), p.append(pe), v.append(ve), a.append(ae), j.append(0.0)
    return t0, p, v, a, j


def _v_min_before(t0: list, v: list, a: list, j: list, dur: float) -> float:
    """Piecewise.v_min as it was before B140, on the same lists."""
    t0 = [x if x < dur else dur for x in t0]
    low = min(v)
    for k in range(len(t0) - 1):
        jk = j[k]
        if jk != 0.0:
            t_zero = -a[k] / jk
            if 0.0 < t_zero < t0[k + 1] - t0[k]:
                x = v[k] - a[k] * a[k] / (2.0 * jk)
                if x < low:
                    low = x
    return low


def _solve(interface: ControlInterface, state: tuple[float, ...]) -> Trajectory | None:
    p0, v0, a0, p1, v1, vmax, amax, jmax = state
    otg, inp = Ruckig(1), InputParameter(1)
    inp.control_interface = interface
    inp.synchronization = Synchronization.Time
    inp.current_position, inp.current_velocity, inp.current_acceleration = [p0], [v0], [a0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [p1], [v1], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [vmax], [amax], [jmax]
    traj = Trajectory(1)
    try:
        return traj if otg.calculate(inp, traj) in (Result.Working, Result.Finished) else None
    except Exception:  # ruckig.RuckigError at a phase boundary (profile._calculate retries those)
        return None


def _states(rng: np.random.Generator, n: int) -> list[tuple[float, ...]]:
    out = []
    for _ in range(n):
        vmax, amax, jmax = rng.uniform(5.0, 200.0), rng.uniform(200.0, 3000.0), rng.uniform(5e3, 1e5)
        v0 = rng.uniform(-0.2, 1.4) * vmax  # above vmax in about one case in seven: a brake pre-phase
        a0 = rng.uniform(-1.3, 1.3) * amax
        v1 = rng.choice([0.0, rng.uniform(0.0, 1.0) * vmax])
        out.append((rng.uniform(-5.0, 5.0), v0, a0, rng.uniform(-5.0, 20.0), v1, vmax, amax, jmax))
    return out


def test_phases_and_lowest_speed_are_the_comprehensions_floats():
    rng = np.random.default_rng(27)
    braked = solved = 0
    for interface in (ControlInterface.Position, ControlInterface.Velocity):
        for state in _states(rng, 300):
            traj = _solve(interface, state)
            if traj is None:
                continue
            solved += 1
            pr = traj.profiles[0][0]
            braked += pr.brake.duration > 0.0
            ref = _phases_before(pr)
            pw = Piecewise.of(traj)
            dur, *rows = pw._lists
            assert dur == float(traj.duration)
            for got, want in zip(rows, ref):
                assert np.array_equal(np.array(got), np.array(want)), (state, got, want)
            assert pw.v_min() == _v_min_before(ref[0], ref[2], ref[3], ref[4], dur), state
            # a later duration (the ramp fallback stretches it): v_min reads the arrays, the start times held to it
            pw.duration = 0.5 * dur
            pw._lists = None
            assert pw.v_min() == _v_min_before(ref[0], ref[2], ref[3], ref[4], 0.5 * dur), state
            for t in np.linspace(-0.01, 0.5 * dur + 0.01, 7):
                s, v, a = pw.sample(np.array([t]))
                assert pw.at(float(t)) == (float(s[0]), float(v[0]), float(a[0])), (state, t)
    assert solved > 500 and braked > 30, (solved, braked)
