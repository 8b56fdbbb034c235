"""Remote I/O stations ([[io]] in a bench file) as MLC X/Y devices, on SimLink (the in-process bus):
the mapping, the latency in cycles, the safe state, and what `hil` shows. The EtherCAT and CANopen
links are in test_ethercat_io.py / test_canopen_io.py.

Latency on SimLink: an input switched on the station before cycle N is read by the user scan of
cycle N (0 cycles); an output the user scan writes in cycle N is on the station's terminal at the
end of cycle N (0 cycles)."""

from __future__ import annotations

import csv
from types import SimpleNamespace

import pytest

from hil.bench_file import BenchFileError, load_bench_file, parse_bench
from hil.scripting import Machine, ScriptError, mlc_setup
from hil.session import make_link
from mlc.machine import Mlc
from tests.conftest import ROOT

BENCH = ROOT / "benches" / "lathe-io.toml"
AXES = '[[axes]]\nname = "X"\nstart = 10.0\n[[spindles]]\nname = "S1"\n'


def loopback_program(log: list):
    """A user MLC: Y(k) = X(k) for the first station, and a log of what each scan saw."""

    def scan(mlc):
        log.append((mlc.scan_count, mlc.x(3), mlc.m("M30032")))
        for k in range(16):
            mlc.y(k, mlc.x(k))
    return SimpleNamespace(scan=scan)


def machine(text: str, program=None, bus: str | None = None) -> Machine:
    bench = parse_bench(text)
    if bus:
        bench.bus = bus
    mlc = Mlc(program, axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config()) if program \
        else mlc_setup(bench, None, None, 0.5)[0]
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    return m


# ---- the bench file ------------------------------------------------------------------------------
def test_stations_take_16_point_blocks_in_order_unless_placed():
    b = parse_bench(AXES + "[[io]]\ninputs = 20\noutputs = 4\n[[io]]\nname = \"valves\"\n"
                           "[[io]]\ninputs = 8\noutputs = 8\nx = 256\ny = 512\n")
    assert [(s.map.name, s.map.x, s.map.inputs, s.map.y, s.map.outputs, s.map.node) for s in b.io] == [
        ("EIO-501", 0, 20, 0, 4, 501), ("valves", 32, 16, 16, 16, 502), ("EIO-503", 256, 8, 512, 8, 503)]
    assert [s.canopen_node for s in b.io] == [64, 65, 66] and b.io[0].canopen_tpdo == "sync"
    shipped = load_bench_file(BENCH)
    assert [s.map.describe() for s in shipped.io] == ["EIO-501 (EIO node 501): X0–X15, Y0–Y15",
                                                      "valves (EIO node 502): X16–X23, Y16–Y23"]


def test_bad_stations_are_reported_per_field():
    text = AXES + ("[[io]]\ninputs = 65\ncanopen_node = 2\ncolour = 1\n"
                   "[[io]]\nx = 1020\ninputs = 8\ncanopen_tpdo = \"sometimes\"\n"
                   "[[io]]\ninputs = 0\noutputs = 0\n")
    with pytest.raises(BenchFileError) as err:
        parse_bench(text)
    msgs = err.value.errors
    assert "io[0].inputs: must be at most 64, got 65" in msgs
    assert "io[0].canopen_node: 2 is taken by a drive (drives are CANopen nodes 1–2) (NC5 alarm 0x1417: " \
        "The slave address is duplicated)" in msgs
    assert "io[0].colour: unknown key" in msgs
    assert any(m.startswith("io[1].canopen_tpdo: must be one of 'sync', 'change'") for m in msgs)
    assert "io: EIO-502: X1020–X1027 runs past X1023" in msgs
    assert "io[2]: a station needs at least one input or output point" in msgs


def test_overlapping_stations_exit_2_naming_both(hil, program, tmp_path):
    bench = tmp_path / "b.toml"
    bench.write_text(AXES + "[[io]]\n[[io]]\nx = 8\n")
    r = hil("run", program("M30\n"), "--bench", bench)
    assert r.code == 2 and "io: EIO-502: X8–X23 overlaps EIO-501 (X0–X15)" in r.err, r.err


# ---- SimLink: inputs to X, Y to outputs, latency -------------------------------------------------
def test_input_is_seen_by_the_same_cycles_scan_and_output_reaches_the_station_that_cycle():
    log: list = []
    m = machine(AXES + "[[io]]\n", loopback_program(log))
    station = m.link.io_devices[0]
    m.cycle(3)
    station.set_input(3, True)
    before = len(log)
    m.cycle(1)
    assert log[before] == (log[before][0], True, True)  # scan of the next cycle reads X3 = 1 (0 cycles)
    assert station.outputs == 0b1000  # Y3 written by that scan is on the terminal in the same cycle
    assert station.history[-1] == (pytest.approx(m.mlc.time), 0b1000)
    station.set_input(3, False)
    m.cycle(1)
    assert log[-1][1] is False and station.outputs == 0
    m.close()


def test_station_off_the_line_reads_zero_and_drops_its_eio_relay():
    log: list = []
    m = machine(AXES + "[[io]]\n[[io]]\n", loopback_program(log))
    first, second = m.link.io_devices
    first.set_input(3, True)
    second.set_input(0, True)
    m.cycle(2)
    assert (m.get("X3"), m.get("X16"), m.get("M30032"), m.get("M30033")) == (1, 1, 1, 1)
    first.connected = False  # the station is gone: its terminals say nothing any more
    m.cycle(1)
    assert (m.get("X3"), m.get("M30032")) == (0, 0)  # safe state: inputs 0, EIO 501 relay off
    assert (m.get("X16"), m.get("M30033")) == (1, 1)  # the other station is untouched
    assert log[-1][1:] == (False, False)  # the user scan saw the safe state
    m.close()


def test_module_api_and_devices_are_the_same_bits():
    seen = []

    def scan(mlc):
        mlc.io.out(1, 2, True)  # station 2, point 2 → Y18
        seen.append((mlc.io.inp(1, 1), mlc.x(17), mlc.m("X17")))
    m = machine(AXES + "[[io]]\n[[io]]\n", SimpleNamespace(scan=scan))
    m.link.io_devices[1].set_input(1, True)
    m.cycle(1)
    assert seen[-1] == (True, True, True)
    assert m.get("Y18") == 1 and m.link.io_devices[1].output(2)
    m.close()


# ---- through hil: bench, lathe MLC, trace columns, script ------------------------------------------
def test_m08_switches_y0_on_the_station_and_the_trace_shows_it(hil, program, tmp_path):
    trace = tmp_path / "t.csv"
    r = hil("run", program("M08\nG04 X0.05\nM09\nM30\n"), "--bench", BENCH, "--trace", trace,
            "--trace-signals", "X0,Y0,M31064,M30032")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    y0 = [int(float(r["Y0"])) for r in rows]
    strobe = [int(float(r["M31064"])) for r in rows]
    on, off = y0.index(1), len(y0) - 1 - y0[::-1].index(1)
    assert strobe[on] == 1 and set(y0[on:off + 1]) == {1} and y0[-1] == 0  # on at M08, off again at M09
    assert 0.045 < (off - on) * 0.001 < 0.06  # the G04 X0.05 between them
    assert {int(float(r["X0"])) for r in rows} == {0}  # nothing drives the pressure switch here
    assert int(float(rows[-1]["M30032"])) == 1  # station 1 connected


def test_script_forces_inputs_and_reads_outputs(hil):
    r = hil("script", ROOT / "examples" / "scripts" / "remote_io.py", "--bench", BENCH,
            "--mlc", ROOT / "examples" / "mlc" / "remote_io.py")
    assert r.code == 0, r.out + r.err
    assert "X2 1 → chuck clamp Y1 1" in r.out and "M08 → coolant Y0 1" in r.out
    assert "pressure X0 1, alarm A1 0" in r.out and "M09 → coolant Y0 0" in r.out


def test_coolant_without_pressure_raises_user_alarm_a1_after_half_a_second():
    m = machine(BENCH.read_text().replace('mlc = "lathe"', f'mlc = "{ROOT / "examples" / "mlc" / "remote_io.py"}"'))
    m.mdi("M08")
    t_on = m.time
    m.wait_until(lambda: m.get("A1") == 1, 2.0, "A1")
    assert 0.49 < m.time - t_on < 0.56
    m.set_input("X0")
    m.cycle(2)
    assert m.get("A1") == 0
    with pytest.raises(ScriptError, match="X99 belongs to no"):
        m.set_input("X99")
    with pytest.raises(ScriptError, match="expected an input"):
        m.set_input("Y0")
    m.close()
