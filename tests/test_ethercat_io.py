"""Remote I/O over EtherCAT: the bench's [[io]] stations are R1-EC class DIO slaves after the drives
on a veth line, exchanged by the pysoem master every cycle and mapped to MLC X/Y devices.

Latency (lock-step, one LRW frame per cycle): an input on the slave's terminals before frame N is
read by the user scan of cycle N (0 cycles); an output the user scan writes in cycle N goes out on
frame N+1 and is in the slave's 0x7000:1 after that frame (1 cycle). A slave that leaves the line:
its X inputs read 0 and its EIO relay drops from the first bad frame on; after the ridden-through
cycles the run stops with 0x1426 (EIO failed). Needs root (veth pair); skipped with the reason."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from fieldbus.ethercat.link import EthercatLink
from fieldbus.link import BusError
from hil.bench_file import parse_bench
from hil.commands.sim import build_chain
from hil.scripting import Machine
from mlc.machine import Mlc
from virtual_bus.ethercat.faults import Fault
from virtual_bus.ethercat.veth import ForkedLine, can_create

REASON = can_create()
pytestmark = pytest.mark.skipif(REASON is not None, reason=REASON or "")

BENCH = """
[[axes]]
name = "X"
start = 10.0
[[spindles]]
name = "S1"
[[io]]
[[io]]
name = "valves"
inputs = 8
outputs = 8
"""


def run_line(faults=(), scans: list | None = None):
    """(bench, chain, machine factory) for the two-station bench; `scans` collects (cycle, X3, X16, M30032)."""
    bench = parse_bench(BENCH)
    chain = build_chain(bench, faults=list(faults))
    log = scans if scans is not None else []

    def scan(mlc):
        log.append((mlc.scan_count, mlc.x(3), mlc.x(16), mlc.m("M30032")))
        for k in range(16):
            mlc.y(k, mlc.x(k))  # station 1 loops its inputs back to its outputs
        mlc.y(16 + 7, mlc.x(16))
    return bench, chain, lambda iface: Machine(bench, Mlc(SimpleNamespace(scan=scan), axes=bench.axis_names,
                                                          cycle=bench.cycle, motion=bench.motion_config()),
                                               EthercatLink.for_bench(bench, iface))


def test_inputs_reach_x_in_the_same_cycle_and_y_reaches_the_slave_one_frame_later():
    scans: list = []
    bench, chain, make = run_line(scans=scans)
    assert [s.name for s in chain.slaves] == ["X", "S1", "EIO-501", "valves"]
    with ForkedLine(chain, "io") as line:
        m = make(line.iface)
        m.power_up()
        m.cycle(5)
        assert (m.get("M30032"), m.get("M30033"), m.get("M30000")) == (1, 1, 1)
        line.set_inputs(0, 0b1000)  # terminal 3 of EIO-501
        line.set_inputs(1, 0b1)  # terminal 0 of "valves"
        n = len(scans)
        m.cycle(1)
        assert scans[n][1:] == (True, True, True)  # the scan of that very cycle saw X3 and X16
        assert line.outputs(0) == 0  # Y3, written in that scan, has not been on the wire yet
        m.cycle(1)
        assert line.outputs(0) == 0b1000 and line.outputs(1) == 0b1000_0000  # Y3 → 0x7000:1 bit 3, Y23 → bit 7
        line.set_inputs(0, 0)
        m.cycle(2)
        assert line.outputs(0) == 0 and m.get("X3") == 0
        m.close()


def test_a_station_leaving_the_line_reads_zero_drops_its_relay_and_raises_0x1426():
    scans: list = []
    bench, chain, make = run_line([Fault("leave", at=300, slave=3)], scans)  # "valves", last on the line
    with ForkedLine(chain, "iol") as line:
        m = make(line.iface)
        m.power_up()
        line.set_inputs(1, 0xFF)
        with pytest.raises(BusError) as err:
            m.cycle(1000)
        m.close()
    assert err.value.alarm.code == 0x1426 and "valves" in err.value.alarm.message
    x16 = [s[2] for s in scans]
    assert x16[10:200] == [True] * 190  # the station's inputs while it was on the line
    assert x16[-1] is False  # after it left: the safe state, before the alarm stopped the scans
    assert m.get("M30033") == 0 and m.get("M30032") == 1  # EIO 502 dropped, EIO 501 still connected


def test_hil_run_over_ethercat_with_the_io_bench(hil, program, tmp_path):
    """`hil sim ethercat --bench benches/lathe-io.toml` serves one R1-EC slave per [[io]] station;
    `hil run` maps them (EIO 501/502 relays on) and switches coolant Y0 through M08/M09."""
    import csv

    from tests.conftest import ROOT
    from virtual_bus.ethercat.veth import SimProcess

    bench = ROOT / "benches" / "lathe-io.toml"
    trace = tmp_path / "ec.csv"
    with SimProcess("--bench", str(bench), tag="ior") as sim:
        r = hil("run", program("M08\nG04 X0.05\nM09\nM30\n"), "--bench", bench, "--bus", f"ethercat:{sim.iface}",
                "--trace", trace, "--trace-signals", "Y0,X0,M30032,M30033")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    y0 = [int(float(r["Y0"])) for r in rows]
    assert 1 in y0 and y0[-1] == 0
    assert int(float(rows[-1]["M30032"])) == 1 and int(float(rows[-1]["M30033"])) == 1
