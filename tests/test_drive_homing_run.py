"""`hil run` homes the axes whose bench entry has a `homing` table (issue 23): each drive runs its own CiA 402
homing (mode 6) before the program, the home position becomes the bench's machine position, and the program then
moves in those coordinates. A drive that cannot home stops the run with an alarm before the program starts."""

from __future__ import annotations

import csv

import pytest

from virtual_bus.ethercat.veth import SimProcess, can_create

CPU = 128_000  # counts per mm: 1 280 000 counts/rev, 10 mm lead
BENCH = """
name = "homing"
bus = "{bus}"
cycle_ms = 1.0
[[axes]]
name = "X"
lead = 10.0
[[axes]]
name = "Z"
lead = 10.0
counts_per_rev = 1280000
start = 60.0
drive = {{ home_switch = {edge}{limit} }}
homing = {{ method = {method}, position = 2.5, switch_rpm = 300, zero_rpm = 30 }}
"""
PROGRAM = "G90 G00 Z10.\nM30\n"


def _run(hil, program, tmp_path, bus="sim", method=21, limit=""):
    bench = tmp_path / "bench.toml"
    bench.write_text(BENCH.format(bus=bus, edge=40 * CPU, method=method, limit=limit))
    trace = tmp_path / "t.csv"
    r = hil("run", program(PROGRAM), "--bench", bench, "--trace", trace)
    return r, list(csv.DictReader(trace.open())) if trace.exists() else []


@pytest.mark.parametrize("bus", ["sim", pytest.param("canopen:virtual", marks=pytest.mark.slow)])  # slow: 10 s under load
def test_run_homes_z_on_its_switch_before_the_program(hil, program, tmp_path, bus):
    r, rows = _run(hil, program, tmp_path, bus)
    assert r.code == 0, r.out + r.err
    x0 = float(rows[0]["Z_act"])
    assert x0 == pytest.approx(60.0, abs=1e-3)  # machine position before homing: where the axis stood
    # The switch edge (40 mm before homing) is now the home position, machine Z = 2.5: the program's Z10
    # ends 7.5 mm beyond the edge, and the axis went there through the switch and back.
    assert float(rows[-1]["Z_act"]) == pytest.approx(10.0, abs=1e-3)
    xs = [float(row["Z_act"]) for row in rows]
    assert min(xs) < 40.0  # onto the switch (its edge at 40 mm in the power-on coordinates) ...
    assert any(abs(float(row["Z_act"]) - 2.5) < 0.01 for row in rows)  # ... and back off it onto the home position


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_run_homes_z_over_ethercat(hil, program, tmp_path):
    """The same homing with the drives behind `hil sim ethercat` on a veth pair: the objects go over CoE in OP,
    mode and controlword in the ASDA_E process data."""
    bench = tmp_path / "bench.toml"
    bench.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    trace = tmp_path / "t.csv"
    with SimProcess("--bench", str(bench), tag="h") as sim:
        r = hil("run", program(PROGRAM), "--bench", bench, "--bus", f"ethercat:{sim.iface}", "--trace", trace)
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    assert float(rows[0]["Z_act"]) == pytest.approx(60.0, abs=1e-3)
    assert float(rows[-1]["Z_act"]) == pytest.approx(10.0, abs=1e-3)
    assert min(float(row["Z_act"]) for row in rows) < 40.0


def test_0x1601_a_limit_switch_met_during_homing_stops_the_run_before_the_program(hil, program, tmp_path):
    """App. A 0x1601 'The hardware limit is triggered during homing ... Check if the homing search direction is
    correct': the home switch (edge at 40 mm) lies beyond the negative limit switch (50 mm), so the drive's search
    meets the limit first and ends homing with an error (statusword bit 13, 0x60FD bit 0); the run stops before
    the program, Z never reaches the program's Z10."""
    r, rows = _run(hil, program, tmp_path, limit=f", negative_limit = {50 * CPU}")
    assert r.code == 1
    assert "ALARM 0x1601" in r.out + r.err and "negative limit switch" in r.out + r.err
    assert min(float(row["Z_act"]) for row in rows) > 49.0


def test_0xde11_a_homing_that_does_not_finish_in_time(tmp_path):
    """deltahil's 0xDE11 stays for a homing the drive does not finish: a 0.2 s timeout for a 20 mm search."""
    from fieldbus.link import SimLink
    from hil.bench_file import load_bench_file
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from nc.program import parse_program

    path = tmp_path / "bench.toml"
    path.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit="").replace("zero_rpm = 30 }",
                                                                                       "zero_rpm = 30, timeout = 0.2 }"))
    bench = load_bench_file(path)
    result = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle)).run_program(parse_program(PROGRAM))
    assert [(a.code, a.axis) for a in result.alarms] == [(0xDE11, "Z")]
    assert "not done within 0.2 s" in result.alarms[0].message


def test_bench_refuses_a_homing_method_the_drive_lacks(hil, program, tmp_path):
    r, _ = _run(hil, program, tmp_path, method=7)
    assert r.code == 2 and "axes[1].homing.method" in r.out + r.err


def test_a_stop_during_homing_brakes_then_disables_at_standstill(tmp_path):
    """A stop request (a signal) while the drive homes: bit 4 drops (CiA 402: homing interrupted, the drive brakes
    on the homing acceleration), the runner waits for standstill, then disables; no alarm."""
    from fieldbus.link import SimLink
    from hil.bench_file import load_bench_file
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from nc.program import parse_program

    path = tmp_path / "bench.toml"
    path.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    bench = load_bench_file(path)
    seen: list[tuple[int, int, int]] = []

    def on_cycle(run: BenchRunner) -> None:
        seen.append((run.tx[1].statusword, run.tx[1].velocity_actual, run.rx[1].mode))
        if run.cycle == 60:
            run.request_stop("SIGINT")

    runner = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle), on_cycle=on_cycle)
    result = runner.run_program(parse_program(PROGRAM))
    assert result.stopped_by == "SIGINT" and not result.alarms
    moving = [k for k, (_, v, _) in enumerate(seen) if v]
    assert seen[59][2] == 6 and abs(seen[59][1]) > 1000  # homing at speed when the stop came
    disabled = next(k for k, (sw, _, _) in enumerate(seen) if k > 60 and sw & 0x6F != 0x27)
    assert moving[-1] < disabled  # it stood before it was disabled
    assert all(sw & 0x3400 == 0x0400 for sw, _, _ in seen[moving[-1]:disabled])  # homing interrupted


def test_a_drive_that_refuses_the_method_raises_0x1604(tmp_path):
    """A drive that aborts the 0x6098 write (a method it lacks: bench files refuse those, a library caller may not)
    gives App. A 0x1604 "The home mode is not supported" before anything moves."""
    import dataclasses

    from fieldbus.link import SimLink
    from hil.bench_file import load_bench_file
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from nc.program import parse_program

    path = tmp_path / "bench.toml"
    path.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    bench = load_bench_file(path)
    z = bench.axes[1]
    bench.axes[1] = dataclasses.replace(z, homing=dataclasses.replace(z.homing, method=7))
    result = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle)).run_program(parse_program(PROGRAM))
    assert [a.code for a in result.alarms] == [0x1604] and "0x06090030" in result.alarms[0].message


def test_no_home_skips_the_drive_homing(hil, program, tmp_path):
    bench = tmp_path / "bench.toml"
    bench.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    trace = tmp_path / "t.csv"
    r = hil("run", program(PROGRAM), "--bench", bench, "--trace", trace, "--no-home")
    assert r.code == 0, r.out + r.err
    zs = [float(row["Z_act"]) for row in csv.DictReader(trace.open())]
    assert min(zs) > 9.9 and zs[-1] == pytest.approx(10.0, abs=1e-3)  # straight from 60 to 10, no homing first


def _no_home(tmp_path, text: str, home: bool = False):
    import hil

    path = tmp_path / "bench.toml"
    path.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    return hil.run(prog, bench=str(path), home=home, check=False)


@pytest.mark.parametrize("block", ["G28 W0.", "G30 P2 Z20.", "G53 Z5."])
def test_0x0a08_machine_coordinate_move_on_an_axis_run_without_homing(tmp_path, block):
    """App. A 0x0A08 'Origin status of the axis is missing. Please execute the homing operation.' and L§G53
    ('before using G53 ... please complete the homing procedure'): Z has a bench `homing` table and the run
    skips it (--no-home), so a return to the reference point (N§3.4 G28/G30) or a G53 move of Z alarms at its
    line when the block is read (G53 stops the look-ahead, so line 1 ran first; G28/G30 are read ahead of
    line 1's motion), and Z never moves towards the reference point or the G53 position: it stays at or
    above line 1's Z30 (power-on Z60)."""
    r = _no_home(tmp_path, f"G00 X5. Z30.\n{block}\nM30\n")
    assert [(a.code, a.line, a.axis) for a in r.alarms] == [(0x0A08, 2, "Z")]
    assert not r.run.finished
    assert 30.0 - 1e-3 <= r.run.final["Z"] <= 60.0 + 1e-3


def test_no_home_leaves_machine_moves_of_axes_without_homing_and_homed_runs_alone(tmp_path):
    """The 0x0A08 check is per axis and per run: G28 X on the --no-home run (X has no homing table, its origin
    is the drive's) and G28 Z on a homed run reach the reference point N2.060 (0 here) without an alarm."""
    r = _no_home(tmp_path, "G28 U0.\nM30\n")
    assert r.alarms == [] and r.run.final["X"] == pytest.approx(0.0, abs=1e-3)
    r = _no_home(tmp_path, "G00 Z30.\nG28 W0.\nM30\n", home=True)
    assert r.alarms == [] and r.run.final["Z"] == pytest.approx(0.0, abs=1e-3)


def test_homing_speeds_go_out_in_the_drives_velocity_unit(tmp_path):
    """The bench's switch_rpm reaches 0x6099 in the unit the drive model declares for its velocities (Delta:
    0.1 rpm, as 0x60FF; a drive in counts/s gets counts/s): either way Z searches its switch at 300 motor rpm
    and homes in the same simulated time."""
    import dataclasses

    from fieldbus.link import SimLink
    from fieldbus.units import DriveUnits
    from hil.bench_file import load_bench_file
    from hil.runner import BenchRunner
    from hil.session import sim_slaves
    from nc.program import parse_program

    path = tmp_path / "bench.toml"
    path.write_text(BENCH.format(bus="sim", edge=40 * CPU, method=21, limit=""))
    homed = {}
    for unit in ("0.1 rpm", "count/s"):
        bench = load_bench_file(path)
        z = bench.axes[1]
        bench.axes[1] = dataclasses.replace(z, scaling=dataclasses.replace(z.scaling, units=DriveUnits(unit)),
                                            homing=dataclasses.replace(z.homing, timeout=10.0))
        rpm: list[float] = []

        def on_cycle(run: BenchRunner) -> None:
            if run.rx[1].mode == 6:
                rpm.append(abs(run.scales[1].drive_to_rpm(run.tx[1].velocity_actual)))

        result = BenchRunner(bench, SimLink(sim_slaves(bench), bench.cycle), on_cycle=on_cycle).run_program(
            parse_program(PROGRAM))
        assert result.ok, (unit, result.alarms)
        assert sorted(rpm)[len(rpm) // 2] == pytest.approx(300.0, abs=0.5), unit  # mostly at the search speed
        homed[unit] = len(rpm)
    assert homed["count/s"] == homed["0.1 rpm"]
    assert homed["0.1 rpm"] * 0.001 > 20 / (300 / 60 * 10)  # at least the 20 mm to the switch at 50 mm/s
