"""Device units end to end (issue 23): a Delta ASDA drive takes 0x60FF and reports 0x606C in 0.1 rpm
of the motor (linuxcnc-ethercat lcec_deasda.c: DEASDA_RPM_FACTOR 0.1), torque 0x6077 in 0.1 % of
rated. S1000 on a 1:1 spindle must reach the drive as 10000 on every bus, and read back the same way;
the trace and the MLC show rpm again."""

from __future__ import annotations

import math

import pytest

from hil.bench import default_lathe
from mlc.signals import d3, m3
from hil.runner import BenchRunner
from hil.scripting import build_mlc
from hil.session import make_link
from nc.program import parse_program
from virtual_bus.ethercat.veth import SimProcess, can_create

PROGRAM = "M03 S1000\nG04 X1.\nM05\nM30\n"
SAMPLE_AT = 0.8  # s: the spindle (1e8 counts/s² ramp) is at speed after ~0.2 s


def _run_s1000(bus: str) -> dict:
    bench = default_lathe()
    bench.bus = bus
    seen: dict = {}

    def sample(r: BenchRunner) -> None:
        if "rx" in seen or r.time < SAMPLE_AT:
            return
        s = len(r.axes)
        seen["rx"] = r.rx[s].target_velocity
        seen["tx"] = r.tx[s].velocity_actual
        seen["rpm"] = r.spindle_actual_rpm()
        seen["torque"] = r.tx[s].torque_actual
        seen["D30340"] = r.mlc.mem.f32(d3(0, 336 + 2 * s))  # velocity RPM of the (s+1)-th drive, to the MLC
        seen["D30240"] = r.mlc.mem.words[30240 + s]  # its torque to the MLC, 0.1 % of rated (s16)
        seen["relays"] = (r.mlc.mem.bit(m3(1, 704)), r.mlc.mem.bit(m3(1, 705)))  # channel 1: S1 speed reached, zero speed
        if not bus.startswith("sim"):  # what the drive itself holds, read over the bus by SDO
            seen["60FF"] = int.from_bytes(r.link.sdo_read(s, 0x60FF, 0), "little", signed=True)
            seen["606C"] = int.from_bytes(r.link.sdo_read(s, 0x606C, 0), "little", signed=True)

    link = make_link(bench)
    result = BenchRunner(bench, link, mlc=build_mlc(bench, "lathe"), on_cycle=sample).run_program(parse_program(PROGRAM))
    assert result.ok, result.alarms
    return seen


def _check(seen: dict) -> None:
    assert seen["rx"] == 10000  # S1000 → 10000 × 0.1 rpm, not counts/s (21 333 333)
    assert seen["tx"] == pytest.approx(10000, abs=2)  # at speed, in the same unit
    assert seen["rpm"] == pytest.approx(1000.0, abs=0.2)  # the master converts back to rpm
    assert seen["D30340"] == pytest.approx(1000.0, abs=0.2)
    assert seen["relays"] == (True, False)  # the MLC's spindle relays judge rpm against S1000 (within 2 %)
    assert 0 < seen["torque"] < 1000  # 0.1 % of rated: a free spindle at speed needs friction torque, well under 100 %
    assert seen["D30240"] == seen["torque"]  # the MLC gets 0x6077 in its own 0.1 % unit, not scaled twice
    if "60FF" in seen:
        assert seen["60FF"] == 10000
        assert seen["606C"] == pytest.approx(10000, abs=2)


def test_s1000_is_10000_tenths_of_rpm_on_sim():
    _check(_run_s1000("sim"))


def test_s1000_is_10000_tenths_of_rpm_on_canopen():
    _check(_run_s1000("canopen:virtual"))


@pytest.mark.skipif(can_create() is not None, reason=can_create() or "")
def test_s1000_is_10000_tenths_of_rpm_on_ethercat():
    with SimProcess(tag="u") as sim:
        _check(_run_s1000(f"ethercat:{sim.iface}"))


def test_trace_shows_rpm(hil, program, tmp_path):
    """The trace's S1 columns are rpm again, and its torque % of rated: 0x6077 comes in 0.1 % units, so a
    spindle held at 1000 rpm against its friction (Coulomb + viscous of the built-in lathe's drive) reads
    that torque over the rated one, about 3 %, not 30 %."""
    trace = tmp_path / "t.csv"
    r = hil("run", program(PROGRAM), "--trace", trace)
    assert r.code == 0, r.out
    import csv

    rows = list(csv.DictReader(trace.open()))
    at_speed = [row for row in rows if float(row["t"]) > SAMPLE_AT][0]
    assert float(at_speed["S1_rpm_cmd"]) == pytest.approx(1000.0)
    assert float(at_speed["S1_rpm_act"]) == pytest.approx(1000.0, abs=0.2)
    p = default_lathe().spindles[0].drive
    friction = p.coulomb + p.viscous * 1000.0 / 60.0 * 2 * math.pi  # N·m at a constant 1000 rpm
    assert float(at_speed["S1_torque"]) == pytest.approx(100.0 * friction / p.rated_torque, abs=0.1)
