"""Issue 5 §4: constant surface speed (G96/G97) on the bench: the spindle drive's commanded speed
follows 1000·V/(π·D) as the tool faces towards the centre, clamped by G50 S."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program

FACING = """G21 G18 G99
G50 S2000
G96 S150 M03
G00 X80. Z2.
G01 Z0. F0.2
X10. F0.1
G97 S500
G00 Z5.
M30
"""


def run(text: str):
    bench = default_lathe()
    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle))
    sc = bench.spindles[0].scaling
    rows = []

    def grab(r):
        if r.channel is not None:
            rows.append((r.line, r._commands[0], sc.counts_per_s_to_rpm(r.rx[2].target_velocity),
                         r.spindle_actual_rpm()))

    runner.on_cycle = grab
    result = runner.run_program(parse_program(text))
    return result, np.array(rows)


def test_facing_under_g96_raises_the_spindle_speed_clamped_by_g50():
    result, rows = run(FACING)
    assert result.ok, result.alarms
    face = rows[rows[:, 0] == 6]
    x, cmd = face[:, 1], face[:, 2]
    d = 2.0 * x  # no offsets: machine X radius = half the work diameter
    want = np.minimum(1000.0 * 150.0 / (math.pi * d), 2000.0)
    # the command tracks the surface-speed law at every cycle (1 count/s of rounding)
    assert np.allclose(cmd, want, rtol=1e-3, atol=0.01)
    # it rises as X falls and stops at the G50 limit
    assert np.all(np.diff(cmd) >= -1e-6)
    assert cmd[0] < 600.0 and cmd.max() == np.float64(cmd.max()) and abs(cmd.max() - 2000.0) < 0.01
    clamped = d < 1000.0 * 150.0 / (math.pi * 2000.0)
    assert clamped.any() and np.allclose(cmd[clamped], 2000.0, atol=0.01)
    # the drive really speeds up, and feed per rev follows its measured speed
    assert face[-1, 3] > 2.0 * face[0, 3]


def test_g97_returns_to_the_programmed_speed():
    result, rows = run(FACING)
    assert result.ok, result.alarms
    after = rows[rows[:, 0] == 8]
    assert abs(after[len(after) // 2, 2] - 500.0) < 0.01


def test_g96_surface_speed_never_exceeds_the_spindle_maximum():
    # without G50 the bench's spindle maximum (4000 rpm) is the clamp, even at the centre
    result, rows = run(FACING.replace("G50 S2000", "(no G50)").replace("X10. F0.1", "X0. F0.1"))
    assert result.ok, result.alarms
    face = rows[rows[:, 0] == 6]
    assert abs(face[:, 2].max() - 4000.0) < 0.01


def test_g50_clamp_also_holds_under_g97(hil, program, tmp_path):
    """A39: G50 S caps the spindle even in constant-rpm mode (lathe manual E-L32)."""
    import csv

    prog = program("G21 G18 G98\nG50 S800\nG97 S1500 M03\nG04 P500\nM05\nM30\n")
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--trace", trace)
    assert r.code == 0, r.out + r.err
    rpm = [float(row["S1_rpm_act"]) for row in csv.DictReader(open(trace))]
    assert max(rpm) == pytest.approx(800.0, rel=0.01)
