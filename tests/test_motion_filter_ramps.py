"""Starts from rest and stops at the end of the motion shaped by the position filter (decision motion 52,
nc.motion.filter_ramps), on benches/mill-3axis.toml (16 + 16 ms filter, N1.053 = 0.02 mm): simulated time,
every cycle within the axis limits (finite differences, jerk included), every setpoint within N1.053 of
the programmed polyline (tests.test_motion_cam.cut asserts both)."""

from __future__ import annotations

import numpy as np

from benchmarks.bench_vs_linuxcnc import START, Program
from hil.bench_file import load_bench_file
from nc.channel import RunState
from nc.motion.offline import run
from tests.motion_helpers import polyline_deviation, worst_ratio
from tests.test_motion_cam import BENCH, cut, moves

TOL = 1.0 + 1e-6


def test_a_line_starts_and_stops_through_the_filter():
    """20 mm at F3000: 0.400 s at the feed plus the filter's 30 cycles of lag and settling. With the
    planner's own ramps (decision 39: 28 ms each at the whole axis jerk) it took 0.460 s; with the
    filter shaping a velocity step of 50 mm/s (3 125 mm/s², 195 000 mm/s³: 0.63 and 0.78 of the X
    limits) 0.433 s."""
    st, _ = cut(Program("line", 3000.0, [(20.0, 0.0, 100.0)]))
    assert st.time <= 0.434 + 1e-9, st.time
    r = worst_ratio(st, load_bench_file(BENCH).motion_config())
    assert 0.70 <= r["j"] <= 0.80 and 0.55 <= r["a"] <= 0.65, r  # the filter's own step response


def test_a_step_the_filter_cannot_take_keeps_the_planned_ramps():
    """At F6000 (100 mm/s) a velocity step leaves the filter as 390 000 mm/s³ on X, over its 250 000: the
    check refuses both the start and the stop, and the planner's own ramps run (0.280 s, as before)."""
    st, _ = cut(Program("fast", 6000.0, [(20.0, 0.0, 100.0)]))
    assert st.time >= 0.275, st.time


def test_a_corner_keeps_its_speed_between_a_filter_start_and_stop():
    """A 90° corner between 10 mm lines at F3000: 0.502 s → 0.460 s (the start from rest, the speed-up out
    of the corner after 8 cycles at its speed, the stop); the corner itself is still crossed at the speed
    the tolerance allows (2.8 mm/s raw, 6.1 mm/s after the filter; the deviation holds, cut). Two corners: the side between them runs
    at the feed (a first form cruised it at the corner's 2.8 mm/s, taking the square 146 s)."""
    st, _ = cut(Program("corner", 3000.0, [(10.0, 0.0, 100.0), (10.0, 10.0, 100.0)]))
    assert st.time <= 0.460 + 1e-9, st.time
    v = np.linalg.norm(np.diff(st.positions, axis=0), axis=1) / st.cycle
    assert v[150:300].min() < 7.0  # slowed at the corner
    st, _ = cut(Program("corners", 3000.0, [(10.0, 0.0, 100.0), (10.0, 10.0, 100.0), (0.0, 10.0, 100.0)]))
    v = np.linalg.norm(np.diff(st.positions, axis=0), axis=1) / st.cycle
    assert st.time <= 0.75 and v[300:400].max() >= 49.9, st.time


def test_a_hold_during_a_filter_start_waits_for_it_then_stops_within_the_limits():
    """A hold in the cycles the filter shapes a start waits until that output is over (span + 4 cycles)
    and then brakes as any hold; resume finishes the program where it is programmed."""
    cfg = load_bench_file(BENCH).motion_config()
    prog = Program("hold", 3000.0, [(20.0, 0.0, 100.0)])
    seen = {}

    def ctl(n, ch):
        if n == 6:
            seen["deferred"] = ch.planner._deferred()
            ch.feed_hold()
        if n == 300:
            seen["pos"], seen["state"] = ch.planner.position.copy(), ch.state
            ch.cycle_start()

    st = run(moves(prog), cfg, dict(zip("XYZ", START)), on_cycle=ctl)
    assert seen["deferred"] and seen["state"] is RunState.HOLD
    assert 1.5 < seen["pos"][0] < 4.0  # the start's 34 cycles at 50 mm/s, then the hold's braking
    assert st.state is RunState.FINISHED and np.allclose(st.positions[-1], [20.0, 0.0, 100.0], atol=1e-9)
    assert max(worst_ratio(st, cfg).values()) <= TOL
    assert polyline_deviation(st.positions, [START] + prog.points) <= cfg.path_tolerance


def test_a_reset_at_the_end_waits_for_the_filter_stop():
    """A reset in the last cycles of a program, while its filter stop runs, lets the stop finish (it is
    shorter than any braking with the planner's limits) and every cycle stays within the limits."""
    cfg = load_bench_file(BENCH).motion_config()
    prog = Program("reset", 3000.0, [(10.0, 0.0, 100.0)])
    during = []

    def ctl(n, ch):
        if n == 190:
            during.append(ch.planner._deferred())  # the stop runs (cycles 180-202)
            ch.reset()

    st = run(moves(prog), cfg, dict(zip("XYZ", START)), on_cycle=ctl)
    assert during == [True]
    assert np.allclose(st.positions[-1], [10.0, 0.0, 100.0], atol=1e-9)
    assert max(worst_ratio(st, cfg).values()) <= TOL
    assert polyline_deviation(st.positions, [START] + prog.points) <= cfg.path_tolerance


def test_stretches_give_the_stepped_trace_where_the_filter_shapes_the_motion(monkeypatch, tmp_path):
    """`hil run` of the R5 chord circle with its lead-in (a filter start, a speed-up out of the 90° corner after
    a wait, a filter stop): with stretches (decisions bench B20-B27, the NC's steps run inside them) the trace
    equals cycle-by-cycle stepping's, column by column. The checks read the filter's state, which a stretch
    filters a part at a time (it must be current at every refill)."""
    from benchmarks.bench_vs_linuxcnc import chord_circle
    from benchmarks.trace_ab import compare, one
    from hil.stretch import ENV

    prog = tmp_path / "r5.nc"
    prog.write_text(chord_circle(5.0).text(lcnc=False))
    out, kept = [], []
    for on in ("0", "1"):
        monkeypatch.setenv(ENV, on)
        out.append(one(str(prog), {"bench": str(BENCH), "trace_signals": None}, tmp_path / f"{on}.parquet", kept))
    assert compare(out[0], out[1]) == []
    assert kept[0].run.stretched == 0 and kept[1].run.stretched > 0.3 * kept[1].run.cycles, kept[1].run.stretched
    assert kept[1].run.ok
