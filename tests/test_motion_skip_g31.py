"""Issue 5 §5: G31 skip in lock-step on the simulated bench. The Z drive has a touch probe wired
(DriveParams.probe_position); the runner arms 0x60B8 while the G31 move is pending and takes the
0x60B9/0x60BA latch as the skip input."""

from __future__ import annotations

import numpy as np

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program

PROGRAM = "G21 G18 G98\nG00 X10. Z2.\nG31 Z-20. F300\n#100=#21049\n#101=#21065\nG01 X20. F200\nM30\n"


def run(probe_z: float | None, text: str = PROGRAM):
    bench = default_lathe()
    zi = bench.axis_names.index("Z")
    if probe_z is not None:
        bench.axes[zi].drive.probe_position = bench.axes[zi].scaling.to_counts(probe_z)
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    rows: list[tuple] = []

    def grab(r):
        if r.channel is not None:
            rows.append((r.line, r._commands[0], r._commands[zi], r.actual[zi]))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    count = 1.0 / bench.axes[zi].scaling.to_counts(1.0)
    return result, np.array(rows), runner, count


def test_g31_stops_at_probe_and_latches_trigger_position():
    result, rows, runner, count = run(-5.0)
    assert result.ok, result.alarms
    ip = runner._interp
    # the latch is the trigger position (±1 count), machine and work (no offsets: equal)
    assert abs(ip.variable(21049) - (-5.0)) <= count
    assert abs(ip.variable(21065) - (-5.0)) <= count
    assert abs(ip.variable(100) - (-5.0)) <= count  # read by the program after the Sync
    assert abs(ip.variable(21048) - 5.0) <= count  # X (radius) did not move during G31
    g31 = rows[rows[:, 0] == 3]
    edge = int(np.argmax(g31[:, 3] <= -5.0))  # first cycle the actual Z is past the probe
    v = np.diff(g31[:, 2])
    # braking starts in the cycle the drive reports the latch: the setpoint slows at once
    assert abs(v[edge - 1]) < abs(v[edge - 2]) - 1e-9
    assert abs(v[edge - 2] - (-300 / 60 * 0.001)) < 1e-9  # full probing speed right before
    stop_z = g31[-1, 2]
    assert -5.1 < stop_z < -5.0  # a short jerk-limited stop, far from the programmed Z-20
    # the next block starts from the stop point: Z stays where G31 stopped while X moves
    nxt = rows[rows[:, 0] == 6]
    assert np.allclose(nxt[:, 2], stop_z, atol=1e-9)
    assert abs(nxt[-1, 1] - 10.0) < 1e-9
    assert abs(result.final["Z"] - stop_z) < 0.002


def test_g31_without_trigger_ends_at_end_point():
    result, rows, runner, count = run(-30.0)
    assert result.ok, result.alarms
    ip = runner._interp
    g31 = rows[rows[:, 0] == 3]
    assert abs(g31[-1, 2] - (-20.0)) < 1e-9
    # no skip signal: the skip variables hold the end point (Delta/Fanuc)
    assert abs(ip.variable(21049) - (-20.0)) <= count
    nxt = rows[rows[:, 0] == 6]
    assert np.allclose(nxt[:, 2], -20.0, atol=1e-9)


def test_g31_twice_latches_each_probe_hit():
    text = ("G21 G18 G98\nG00 X10. Z2.\nG31 Z-20. F300\n#100=#21049\nG00 Z2.\n"
            "G31 Z-20. F150\n#101=#21049\nM30\n")
    result, rows, runner, count = run(-5.0, text)
    assert result.ok, result.alarms
    assert abs(runner._interp.variable(100) + 5.0) <= count
    assert abs(runner._interp.variable(101) + 5.0) <= count
