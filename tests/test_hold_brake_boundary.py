"""A feed hold that lands while the path brakes at its full deceleration (decision motion 62).

There the state sits on ruckig's phase boundary — v0 = a0²/2j to the last bit — and ruckig 0.19 threw in
`solve_velocity`: the run ended with 0x0000 "NC internal error" and a quick stop that ran the axes past the
programmed end point (found by a campaign: the examples on the mill bench with a feed-hold fault)."""

from __future__ import annotations

import csv
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hil.cli import main
from nc.motion.profile import solve_axes, solve_velocity
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")


def _check_ramp(v0: float, a0: float, a_max: float, j_max: float) -> None:
    pw = solve_velocity(10.0, v0, a0, 0.0, a_max, j_max)
    t = np.linspace(0.0, pw.duration, 401)
    p, v, a = pw.sample(t)
    assert abs(v[-1]) < 1e-9 and abs(a[-1]) < 1e-6 * a_max
    assert v.min() > -1e-12 and np.all(np.diff(p) >= -1e-12)  # the hold never backs along the path
    assert np.abs(a).max() <= a_max * (1 + 1e-9)


def test_the_state_the_campaign_found_ramps_to_rest():
    # the rapid of lathe_face_drilling_c.nc line 2 on mill-3axis, held at t=0.5 s while braking
    _check_ramp(22.42270674512304, -2242.270674512285, 2242.270674512285, 112113.5337256143)


def test_an_independent_axis_rapid_held_while_braking_ramps_to_rest():
    # the same state on one axis of a non-interpolated G00 (planner._plan_indep's hold: solve_axes, velocity)
    v0, a0, a_max, j_max = 22.42270674512304, -2242.270674512285, 2242.270674512285, 112113.5337256143
    pw = solve_axes([1.0, 5.0], [v0, 0.0], [a0, 0.0], [1.0, 5.0], [v0, 500.0], [a_max, 5000.0],
                    [j_max, 250000.0], velocity=True)
    p, v, a = pw.sample(np.linspace(0.0, pw.duration, 201))
    assert abs(v[-1]) < 1e-9 and v.min() > -1e-12 and abs(pw.duration - 0.02) < 1e-9


@settings(max_examples=400, deadline=None)
@given(a_max=st.floats(100.0, 20000.0), jerk_time=st.floats(0.002, 0.05),
       share=st.one_of(st.just(1.0), st.floats(0.3, 1.0)),  # 1.0: braking at a_max, where ruckig threw
       ulps=st.integers(-6, 6))
def test_a_hold_while_braking_exactly_to_rest_is_always_planned(a_max, jerk_time, share, ulps):
    j_max = a_max / jerk_time
    a0 = -a_max * share
    v0 = a0 * a0 / (2.0 * j_max)  # the jerk-down from a0 ends exactly at v = 0
    for _ in range(abs(ulps)):
        v0 = math.nextafter(v0, math.inf if ulps > 0 else 0.0)
    _check_ramp(v0, a0, a_max, j_max)


def test_a_feed_hold_during_the_rapids_deceleration_holds_and_resumes(tmp_path, capsys):
    prog = tmp_path / "p.nc"
    prog.write_text("G90 G54 G17 G21 G94\nG00 X100. Z10.\nG01 X90. F3000\nM30\n")
    trace = tmp_path / "t.csv"
    code = main(["run", str(prog), "--bench", MILL, "--trace", str(trace), "--at", "t=0.5:feed-hold",
                 "--at", "t=1.0:cycle-start"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "0x0000" not in out and "result         completed" in out
    rows = list(csv.DictReader(open(trace)))
    x = np.array([float(r["X_cmd"]) for r in rows])
    z = np.array([float(r["Z_cmd"]) for r in rows])
    assert x.max() <= 100.0 + 1e-9 and z.min() >= 10.0 - 1e-9  # never past the rapid's end point
    assert abs(x[-1] - 90.0) < 1e-9 and abs(z[-1] - 10.0) < 1e-9
