"""Issue 2: the bench skeleton — drives enable, setpoints respect limits, standstill has no following error."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from fieldbus.cia402 import Cia402Master, State, Target, decode_state
from fieldbus.link import SimLink
from fieldbus.pdo import ASDA_CSP, ASDA_CSP_CSV, RxPdo, TxPdo
from fieldbus.units import AxisScaling
from hil.bench import default_lathe
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program
from tests.conftest import ROOT
from virtual_bus.drive import AL_FOLLOWING_ERROR, Cia402Drive

DEMO = ROOT / "examples" / "lathe_demo.nc"


def run(text: str, **bench_kw):
    bench = default_lathe()
    for k, v in bench_kw.items():
        setattr(bench, k, v)
    link = SimLink(sim_slaves(bench), bench.cycle)
    runner = BenchRunner(bench, link)
    setpoints: list[np.ndarray] = []
    runner.on_cycle = lambda r: setpoints.append(r._commands.copy()) if r.channel is not None else None
    result = runner.run_program(parse_program(text))
    return result, np.array(setpoints), bench


def test_drives_reach_operation_enabled_within_bounded_cycles():
    bench = default_lathe()
    drives = sim_slaves(bench)
    link = SimLink(drives, bench.cycle)
    runner = BenchRunner(bench, link)
    assert runner.power_up()
    # disabled -> ready -> switched on -> enabled: one transition per cycle, plus one to read back
    assert runner.result.enable_cycles <= 5
    assert all(d.state is State.OPERATION_ENABLED for d in drives)


def test_master_state_machine_walks_the_standard_transitions():
    drive = Cia402Drive()
    master = Cia402Master(target=Target.ENABLED)
    seen = []
    tx = drive.feedback()
    for _ in range(6):
        cw = master.step(tx.statusword)
        tx = drive.exchange(RxPdo(controlword=cw, target_position=tx.position_actual), 0.001)
        seen.append(decode_state(tx.statusword))
    assert seen[:3] == [State.READY_TO_SWITCH_ON, State.SWITCHED_ON, State.OPERATION_ENABLED]
    master.request(Target.QUICK_STOP)
    cw = master.step(tx.statusword)
    assert cw == 0x0002
    tx = drive.exchange(RxPdo(controlword=cw, target_position=tx.position_actual), 0.001)
    assert decode_state(tx.statusword) in (State.QUICK_STOP_ACTIVE, State.SWITCH_ON_DISABLED)


def test_fault_reset_after_following_error_fault():
    drive = Cia402Drive()
    master = Cia402Master(target=Target.ENABLED)
    tx = drive.feedback()
    for _ in range(5):
        tx = drive.exchange(RxPdo(controlword=master.step(tx.statusword), target_position=tx.position_actual), 0.001)
    # a setpoint jump of 100 motor revolutions cannot be followed: the drive faults with AL009
    for _ in range(1000):  # fault reaction brakes at the quick-stop deceleration, then reports FAULT
        tx = drive.exchange(RxPdo(controlword=master.step(tx.statusword), target_position=128_000_000), 0.001)
        if decode_state(tx.statusword) is State.FAULT:
            break
    assert decode_state(tx.statusword) is State.FAULT
    assert abs(tx.velocity_actual) < 1
    assert tx.error_code == AL_FOLLOWING_ERROR
    master.fault_reset()
    for _ in range(6):
        tx = drive.exchange(RxPdo(controlword=master.step(tx.statusword), target_position=tx.position_actual), 0.001)
    assert decode_state(tx.statusword) is State.OPERATION_ENABLED
    assert tx.error_code == 0


def test_program_final_position_and_standstill_following_error():
    result, sp, bench = run("G98\nG00 X40. Z20.\nG01 Z-10. F1200\nG02 X60. Z-20. R10.\nG04 P100\n")
    assert result.ok, result.alarms
    assert result.final["X"] == pytest.approx(30.0, abs=1e-4)
    assert result.final["Z"] == pytest.approx(-20.0, abs=1e-4)
    # in motion the loop lags, at standstill the drive holds the command to the count
    assert result.max_ferr["Z"] > 0.001
    assert sp[-1] == pytest.approx([30.0, -20.0], abs=1e-9)


def test_setpoint_stream_respects_velocity_acceleration_and_jerk_limits():
    result, sp, bench = run(DEMO.read_text())
    assert result.ok, result.alarms
    dt = bench.cycle
    v = np.diff(sp, axis=0) / dt
    a = np.diff(v, axis=0) / dt
    j = np.diff(a, axis=0) / dt
    for i, ax in enumerate(bench.axes):
        lim = ax.limits
        assert np.max(np.abs(v[:, i])) <= lim.max_velocity * (1 + 1e-6)
        assert np.max(np.abs(a[:, i])) <= lim.max_acceleration * (1 + 1e-6)
        assert np.max(np.abs(j[:, i])) <= lim.max_jerk * (1 + 1e-6)
    # and the limits are actually used, so the check is not vacuous
    assert np.max(np.abs(v)) > 0.5 * min(ax.limits.max_velocity for ax in bench.axes)


def test_feed_rate_is_held_on_a_long_line():
    result, sp, bench = run("G98\nG00 X40. Z0.\nG01 Z-100. F3000\n")
    cut = sp[sp[:, 1] < -0.5]  # the G01 part, after the rapid to Z0
    v = np.abs(np.diff(cut[:, 1])) / bench.cycle
    assert np.max(v) == pytest.approx(50.0, rel=1e-6)  # F3000 mm/min = 50 mm/s
    assert np.sum(np.isclose(v, 50.0, rtol=1e-6)) > 1500  # cruising for most of the 2 s move


def test_demo_run_writes_a_trace_of_every_cycle(hil, tmp_path):
    trace = tmp_path / "demo.csv"
    r = hil("run", DEMO, "--trace", trace)
    assert r.code == 0, r.out + r.err
    assert "alarms         none" in r.out
    rows = list(csv.DictReader(open(trace)))
    cols = set(rows[0])
    for ax in ("X", "Z"):
        assert {f"{ax}_cmd", f"{ax}_act", f"{ax}_vel", f"{ax}_torque", f"{ax}_ferr", f"{ax}_sw"} <= cols
    t = np.array([float(r["t"]) for r in rows])
    assert np.allclose(np.diff(t), 0.001)
    cycles = int(r.out.split("cycles")[1].split()[0])
    assert len(rows) == cycles
    assert {int(r["line"]) for r in rows} >= {5, 9, 13, 19}
    # the spindle ran at the programmed 1200 rpm during the cut
    rpm = np.array([float(r["S1_rpm_act"]) for r in rows])
    assert np.max(rpm) == pytest.approx(1200.0, rel=0.01)


def test_drive_fault_mid_program_stops_everything_with_servo_alarm():
    bench = default_lathe()
    drives = sim_slaves(bench)
    link = SimLink(drives, bench.cycle)
    runner = BenchRunner(bench, link)
    log: list[tuple[float, float]] = []

    def inject(r: BenchRunner) -> None:
        if r.cycle == 400:
            drives[1].external_fault = 0x0021  # Z drive reports an encoder alarm
        log.append((r.cycle, drives[0].velocity))

    runner.on_cycle = inject
    result = runner.run_program(parse_program("G98\nG00 X0. Z-200.\n"))
    assert not result.ok
    servo = [a for a in result.alarms if a.code == 0xF002]
    assert servo and servo[0].axis == "Z" and servo[0].info == 0x21
    # X decelerated under control and stands still at the end: below what its 0x606C can show (0.1 rpm)
    assert abs(drives[0].velocity) < drives[0].params.counts_per_rev / 600
    vx = np.array([v for c, v in log if c > 400])
    assert np.all(np.abs(np.diff(vx)) < 2e6)  # no step: a ramp, not a jump (counts/s per cycle)


def test_pdo_layouts_pack_round_trip():
    rx = RxPdo(controlword=0x000F, target_position=-123456, mode=8, target_velocity=-5000)
    tx = TxPdo(statusword=0x1237, position_actual=2**31 - 1, velocity_actual=-7, torque_actual=-250,
               following_error=-3, error_code=0x0009)
    assert ASDA_CSP.rx_bytes == 7 and ASDA_CSP.tx_bytes == 18
    assert ASDA_CSP.unpack_rx(ASDA_CSP.pack_rx(rx)).target_position == -123456
    back = ASDA_CSP_CSV.unpack_tx(ASDA_CSP_CSV.pack_tx(tx))
    assert (back.position_actual, back.torque_actual, back.error_code) == (2**31 - 1, -250, 9)


def test_unit_scaling():
    s = AxisScaling(counts_per_rev=1_280_000, gear_motor=3, gear_load=1, lead=10.0)
    assert s.to_counts(1.0) == 384_000
    assert s.to_units(384_000) == pytest.approx(1.0)
    spindle = AxisScaling(counts_per_rev=1_280_000, lead=360.0)
    # Delta drives carry velocity in 0.1 rpm of the motor (lcec_deasda.c DEASDA_RPM_FACTOR 0.1)
    assert spindle.rpm_to_drive(60.0) == 600 and spindle.drive_to_rpm(600) == pytest.approx(60.0)
    assert s.velocity_to_drive(10.0) == 1800  # 10 mm/s at 10 mm/rev, 3:1 gear: 180 motor rpm
    assert s.drive_to_velocity(1800) == pytest.approx(10.0)


def test_trace_directory_is_created(hil, tmp_path):
    trace = tmp_path / "new" / "dir" / "demo.csv"
    r = hil("run", ROOT / "examples" / "lathe_demo.nc", "--trace", trace)
    assert r.code == 0 and trace.exists()
