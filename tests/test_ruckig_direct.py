"""ruckig's C++ called directly for the 1-DoF solves (nc/motion/ruckig_direct.pyx, decision bench B162) against
ruckig's Python module: the same phases, duration and highest position to the bit, the same states unsolved, for
position and velocity control, braking pre-phases (a0 beyond a_max, v0 beyond v_max), targets behind, zero-length
moves, and the states where ruckig throws (profile._calculate's retries)."""

from __future__ import annotations

import math

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from ruckig import ControlInterface, InputParameter, Result, Ruckig, Synchronization, Trajectory

from nc.motion import compiled, profile
from nc.motion.profile import Piecewise

direct = profile._DIRECT
if direct is not None:
    from nc.motion import ruckig_direct
needs_direct = pytest.mark.skipif(direct is None, reason=f"ruckig's C++ is not called directly here ({profile.RUCKIG})")
ULP = 2.220446049250313e-16


def _pybind(velocity: bool, p0: float, v0: float, a0: float, p1: float, v1: float, v_max: float, a_max: float,
            j_max: float, traj: Trajectory | None = None) -> tuple[tuple | None, int]:
    """The reference: a fresh Ruckig and InputParameter of ruckig's Python module and a fresh Trajectory (or `traj`,
    refilled as profile.py's pooled one), retried as profile._calculate retries, read back by Piecewise.of; with how
    many calculates threw."""
    otg, inp = Ruckig(1), InputParameter(1)
    pooled = traj
    inp.control_interface = ControlInterface.Velocity if velocity else ControlInterface.Position
    inp.synchronization = Synchronization.Time
    inp.current_position, inp.current_velocity, inp.current_acceleration = [p0], [v0], [a0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [p1], [v1], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v_max], [a_max], [j_max]
    a = [a0 * (1.0 - 1e-12)]
    for thrown, (acc, jerk) in enumerate((([a0], [j_max]), (a, [j_max]), (a, [j_max * (1.0 - 1e-9)]))):
        inp.current_acceleration, inp.max_jerk = acc, jerk
        traj = Trajectory(1) if pooled is None else pooled
        try:
            res = otg.calculate(inp, traj)
        except Exception:  # ruckig.RuckigError: the next retry
            continue
        if res not in (Result.Working, Result.Finished):
            return None, thrown
        pw = Piecewise.of(traj)
        return (pw._lists[1:], pw.duration, pw.p_max), thrown
    return None, 3


def _bits(answer: tuple | None) -> object:
    """Every double as its hex (−0.0 apart from 0.0, NaN by its bits' text), the rows' lengths kept."""
    if answer is None:
        return None
    rows, duration, p_max = answer
    return [[x.hex() for x in row] for row in rows], duration.hex(), p_max.hex()


def _check(velocity: bool, *args: float) -> int:
    """One solve both ways from a fresh trajectory (ruckig's velocity control leaves the final position the solve
    before set: p_max includes it; the sequence test below compares that history)."""
    ruckig_direct.reset()
    want, thrown = _pybind(velocity, *args)
    got = direct(velocity, *args)
    assert _bits(got) == _bits(want), (velocity, args)
    return thrown


finite = dict(allow_nan=False, allow_infinity=False)
states = dict(p0=st.floats(-500.0, 500.0, **finite),
              v0=st.one_of(st.just(0.0), st.just(-0.0), st.floats(-400.0, 400.0, **finite)),
              a0=st.one_of(st.just(0.0), st.just(-0.0), st.floats(-8000.0, 8000.0, **finite)),
              dist=st.one_of(st.just(0.0), st.just(-0.0), st.just(ULP), st.floats(-50.0, 50.0, **finite)),
              v1=st.one_of(st.just(0.0), st.floats(-300.0, 300.0, **finite)),
              v_max=st.one_of(st.just(0.0), st.just(1e-9), st.floats(0.1, 300.0, **finite)),
              a_max=st.floats(10.0, 5000.0, **finite), jerk_time=st.floats(0.001, 0.2, **finite))


@needs_direct
@settings(max_examples=1500, deadline=None)
@given(velocity=st.booleans(), **states)
@example(velocity=False, p0=0.0, v0=0.0, a0=0.0, dist=1.2 + ULP, v1=0.0, v_max=50.0, a_max=1500.0, jerk_time=0.02)
@example(velocity=False, p0=3.0, v0=120.0, a0=4000.0, dist=-2.0, v1=0.0, v_max=50.0, a_max=1500.0, jerk_time=0.02)
def test_a_direct_solve_is_the_python_modules_to_the_bit(velocity, p0, v0, a0, dist, v1, v_max, a_max, jerk_time):
    # v1 may exceed v_max (ruckig refuses the input: None both ways) and p1 lie behind p0
    _check(velocity, p0, v0, a0, p0 + dist, v1, v_max, a_max, a_max / jerk_time)


@needs_direct
def test_braking_pre_phases_and_retries_are_among_the_compared_states():
    """The branches the hypothesis test is meant to reach, reached on purpose: a brake pre-phase where the start
    exceeds the limits, and ruckig throwing at a phase boundary (one retry; decision motion 62's feed hold)."""
    for v0, a0 in ((90.0, 0.0), (20.0, 3000.0), (-70.0, -2500.0)):
        args = (1.0, v0, a0, 6.0, 0.0, 50.0, 1500.0, 75000.0)
        _check(False, *args)
        _check(True, *args)
        want, _ = _pybind(False, *args)
        rows = want[0]
        assert len(rows[0]) > 2 and rows[3][0] == a0  # the profile starts from the state itself, braking
    _check(False, 0.0, 0.0, 0.0, 1.2 + ULP, 0.0, 50.0, 1500.0, 75000.0)  # (threw in ruckig 0.19 after other solves)
    # braking at a_max exactly to rest (decision motion 62): thrown once, then solved with a0 1e-12 nearer zero
    v0, a0, a_max, j_max = 22.42270674512304, -2242.270674512285, 2242.270674512285, 112113.5337256143
    assert _check(True, 10.0, v0, a0, 10.0, 0.0, v0, a_max, j_max) == 1
    assert _check(True, 10.0, 340.1283551601628, -19476.00211108957, 10.0, 0.0, 340.1283551601628,
                  19476.00211108957, 557605.1694551461) == 1
    # a target velocity beyond v_max: ruckig refuses the input (thrown, retried, thrown), None both ways
    assert _check(False, 0.0, 0.0, 0.0, 1.0, 80.0, 50.0, 1500.0, 75000.0) == 3


@needs_direct
def test_a_sequence_of_solves_through_one_trajectory_is_the_python_modules_to_the_bit():
    """profile.py refills one pooled Trajectory for every 1-DoF solve; ruckig_direct one C++ trajectory. A velocity
    solve's p_max includes the final position the solve before it left (ruckig keeps none for velocity control):
    the same sequence gives the same bits, thrown and refused solves among it."""
    import random
    rng = random.Random(162)
    ruckig_direct.reset()
    traj = Trajectory(1)
    seen_pf = 0
    for _ in range(3000):
        velocity = rng.random() < 0.4
        p0 = rng.uniform(-50.0, 50.0)
        v_max = rng.choice([0.0, 50.0, rng.uniform(1.0, 100.0)])
        a_max = rng.choice([1500.0, rng.uniform(100.0, 3000.0)])
        args = (p0, rng.uniform(-120.0, 120.0), rng.choice([0.0, rng.uniform(-4000.0, 4000.0)]),
                p0 + rng.choice([0.0, rng.uniform(-10.0, 10.0)]), rng.choice([0.0, rng.uniform(-60.0, 60.0)]),
                v_max, a_max, a_max / rng.uniform(0.005, 0.05))
        want, _ = _pybind(velocity, *args, traj=traj)
        got = direct(velocity, *args)
        assert _bits(got) == _bits(want), (velocity, args)
        if velocity and want is not None and want[2] > max(max(want[0][1]), args[0]):
            seen_pf += 1  # the highest position is the earlier solve's target, not this ramp's
    assert seen_pf > 50


@needs_direct
def test_a_one_axis_independent_rapid_is_the_python_modules_to_the_bit():
    for velocity in (False, True):
        for args in (([1.0], [30.0], [-900.0], [4.0], [50.0], [1500.0], [75000.0]),
                     ([0.0], [0.0], [0.0], [-2.5], [100.0], [2000.0], [1e5])):
            ruckig_direct.reset()
            got = profile.solve_axes(*args, velocity=velocity)
            p0, v0, a0, p1, v_max, a_max, j_max = (x[0] for x in args)
            want, _ = _pybind(velocity, p0, v0, a0, p1, 0.0, v_max, a_max, j_max)
            assert _bits((got._lists[1:], got.duration, got.p_max)) == _bits(want)


@needs_direct
def test_the_planners_solves_go_through_the_direct_path():
    calls = []

    def counting(*args: float) -> object:
        calls.append(args)
        return direct(*args)

    profile._DIRECT = counting
    ruckig_direct.reset()
    try:
        pw = profile.solve_position(0.5, 3.0, 100.0, 9.5, 0.0, 40.0, 1500.0, 75000.0)
        ramp = profile.solve_velocity(2.0, 30.0, -200.0, 0.0, 1500.0, 75000.0)
    finally:
        profile._DIRECT = direct
    assert [c[0] for c in calls] == [False, True]
    traj = Trajectory(1)  # one trajectory for both, as profile.py's pool
    for pwk, (velocity, *args) in ((pw, calls[0]), (ramp, calls[1])):
        want, _ = _pybind(velocity, *args, traj=traj)
        assert _bits((pwk._lists[1:], pwk.duration, pwk.p_max)) == _bits(want)
    assert abs(ramp.v_end()) < 1e-9 and math.isclose(pw.at(pw.duration)[0], 9.5, abs_tol=1e-9)


def test_the_python_planner_solves_through_ruckigs_python_module(monkeypatch):
    monkeypatch.setenv(compiled.ENV, "1")
    assert compiled.direct_ruckig("0.19.4") == (None, f"pybind ({compiled.ENV}=1)")


def test_a_build_for_another_ruckig_is_not_used(monkeypatch):
    monkeypatch.delenv(compiled.ENV, raising=False)
    if compiled.direct_state(compiled.HERE) != "direct":
        pytest.skip(f"ruckig_direct is not built here ({compiled.direct_state(compiled.HERE)})")
    from nc.motion import ruckig_direct
    solve, state = compiled.direct_ruckig(ruckig_direct.RUCKIG_VERSION)
    assert state == "direct" and solve is ruckig_direct.solve
    solve, state = compiled.direct_ruckig("0.0.1")
    assert solve is None and state == (f"pybind (ruckig_direct is built for ruckig {ruckig_direct.RUCKIG_VERSION}, "
                                       "ruckig 0.0.1 runs)")


def test_direct_state_of_a_folder(tmp_path):
    suffix = __import__("importlib.machinery").machinery.EXTENSION_SUFFIXES[0]
    assert compiled.direct_state(tmp_path).startswith("pybind (ruckig_direct not compiled")
    for name in compiled.DIRECT_SOURCES:
        (tmp_path / name).write_text("")
    build = tmp_path / f"ruckig_direct{suffix}"
    build.write_text("")
    assert compiled.direct_state(tmp_path) == "direct"
    t = build.stat().st_mtime
    import os
    os.utime(tmp_path / "ruckig_direct.hpp", (t + 60.0, t + 60.0))
    assert compiled.direct_state(tmp_path).startswith("pybind (ruckig_direct.hpp is newer than its build")
