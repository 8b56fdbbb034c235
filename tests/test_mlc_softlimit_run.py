"""Software limits through `hil run`: the bench's axis soft_limits and G10 L21 (NC5 §3.8.3.7).

A move that would cross a limit raises 0x0A01 (1st segment) / 0x0A03 (2nd segment) before it starts:
the axes end where the last legal move left them and the trace never shows a position past the limit.
"""

from __future__ import annotations

import csv

from nc.moves import Move
from nc.softlimits import SoftLimits

BENCH = """\
name = "softlimit-lathe"
profile = "nc5-lathe-a"
bus = "sim"
cycle_ms = 1.0

[[axes]]
name = "X"
lead = 5.0
start = 20.0
soft_limits = [-5.0, 60.0]

[[axes]]
name = "Z"
lead = 10.0
start = 50.0
soft_limits = [-100.0, 80.0]
"""


def _run(hil, tmp_path, text: str):
    bench = tmp_path / "bench.toml"
    bench.write_text(BENCH)
    prog = tmp_path / "p.nc"
    prog.write_text("G98\n" + text)  # feed per minute: no spindle on this bench
    trace = tmp_path / "t.csv"
    r = hil("run", prog, "--bench", bench, "--trace", trace)
    with open(trace) as f:
        rows = list(csv.DictReader(f))
    return r, rows


def _col(rows, name):
    return [float(r[name]) for r in rows]


def test_crossing_the_bench_limit_alarms_before_the_move_and_nothing_moves(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "G01 W40. F600\nM30\n")  # Z 50 → 90 crosses +80
    assert r.code == 1
    assert "0x0A01" in r.out and "axis Z" in r.out and "line 2" in r.out
    z = _col(rows, "Z_cmd")
    assert max(z) == min(z) == 50.0  # not a single setpoint left the start
    assert abs(_col(rows, "Z_act")[-1] - 50.0) < 1e-3


def test_legal_moves_before_the_crossing_one_run_out_first(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "G01 W20. F600\nG01 W20.\nM30\n")  # 50 → 70 ok, 70 → 90 crosses
    assert r.code == 1 and "0x0A01" in r.out and "line 3" in r.out
    z = _col(rows, "Z_cmd")
    assert abs(max(z) - 70.0) < 1e-9 and abs(z[-1] - 70.0) < 1e-9


def test_g10_l21_sets_the_limit_x_as_a_diameter(hil, tmp_path):
    # P1 = 1st positive limit; X100. is a diameter → radius 50, below the bench's 60.
    r, rows = _run(hil, tmp_path, "G10 L21 P1 X100.\nG01 U10. F300\nG01 X110.\nM30\n")
    assert r.code == 1 and "0x0A01" in r.out and "axis X" in r.out and "line 4" in r.out
    x = _col(rows, "X_cmd")
    assert abs(max(x) - 25.0) < 1e-9  # X20 radius + U10 (diameter) = radius 25; X110 never started


def test_g10_l21_second_segment_raises_0a03(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "G10 L21 P4 Z30.\nG01 W-30. F600\nM30\n")  # 2nd negative limit Z30: 50 → 20 crosses
    assert r.code == 1 and "0x0A03" in r.out and "axis Z" in r.out
    assert min(_col(rows, "Z_cmd")) == 50.0


def test_a_program_inside_the_limits_finishes(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "G01 W25. F600\nG01 U-10.\nM30\n")
    assert r.code == 0, r.out
    assert abs(_col(rows, "Z_cmd")[-1] - 75.0) < 1e-9


def test_an_arc_bulging_past_a_limit_is_caught_though_its_end_points_are_inside():
    lim = SoftLimits({"X": (-5.0, 60.0), "Z": (-100.0, 80.0)})
    # Half circle in the ZX plane from Z0 to Z40 around Z20, radius 20, X at 45 → top at X 65.
    arc = Move("arc", 7, "G02", {"X": 45.0, "Z": 0.0}, {"X": 45.0, "Z": 40.0}, {}, center={"X": 45.0, "Z": 20.0},
               dir="cw", plane=("Z", "X"))
    al = lim.check(arc)
    assert al is not None and al.code == 0x0A01 and al.axis == "X" and al.line == 7
    other_way = Move("arc", 8, "G03", arc.start, arc.end, {}, center=arc.center, dir="ccw", plane=("Z", "X"))
    assert lim.check(other_way) is None  # bottom half reaches X 25 only
