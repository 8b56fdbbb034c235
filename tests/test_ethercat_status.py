"""M30000 (EtherCAT communication status) and the EIO relays M30032+k follow the link's real
state: 1 while every slave is in OP, 0 once a slave has left the line (issue 6). The EtherCAT
tests need root (veth pair) and are skipped with the reason otherwise."""

from __future__ import annotations

import csv

import pytest

from fieldbus.link import LinkStatus
from mlc.machine import Mlc
from virtual_bus.ethercat.veth import SimProcess, can_create
from virtual_bus.io import IoModule

REASON = can_create()
needs_veth = pytest.mark.skipif(REASON is not None, reason=REASON or "")

# ~1.2 s of motion on X and Z with the spindle running (as test_ethercat_faults.py)
PROGRAM = "G21 G18 G98\nS500 M03\nG01 X80. Z50. F3000\nG01 X100. Z80. F3000\nM30\n"


def column(path, name: str) -> list[int]:
    rows = list(csv.DictReader(path.open()))
    return [int(float(r[name])) for r in rows]


def scanned(values: list[int]) -> list[int]:
    """The rows from the MLC's first scan on (power-up cycles run before the MLC scans)."""
    first = next(k for k, v in enumerate(values) if v)
    return values[first:]


def test_m30000_is_on_for_a_whole_sim_run(hil, program, tmp_path):
    trace = tmp_path / "t.csv"
    r = hil("run", program(PROGRAM), "--mlc", "lathe", "--trace-signals", "M30000,M30032", "--trace", trace)
    assert r.code == 0, r.out + r.err
    m30000 = column(trace, "M30000")
    assert len(scanned(m30000)) > 1000 and set(scanned(m30000)) == {1}
    assert set(column(trace, "M30032")) == {0}  # no EIO node on this bench


def test_eio_relays_follow_the_bus_io_slaves_and_in_process_modules():
    from nc.channel import Channel
    from nc.motion import Planner
    from nc.motion.limits import MotionConfig

    mlc = Mlc()
    mlc.io_modules = [IoModule(), IoModule(name="EIO-502", node=502), IoModule(name="EIO-503", node=503)]
    mlc.io_modules[2].connected = False  # type: ignore[attr-defined]
    ch = Channel(Planner(MotionConfig(cycle=0.001, axes=("X", "Z")), {"X": 0.0, "Z": 0.0}))
    mlc.bus_status(LinkStatus(False, ["X", "Z", "S1", "R1-EC", "R1-EC"], ["drive", "drive", "drive", "io", "io"],
                              ["OP", "OP", "OP", "OP", "SAFE-OP+ERR"]))
    mlc.scan(ch)
    assert [mlc.get(f"M{30032 + k}") for k in range(4)] == [1, 0, 0, 0]
    assert mlc.get("M30000") == 0
    mlc.bus_status(LinkStatus(True, ["X", "R1-EC"], ["drive", "io"], ["OP", "OP"]))
    mlc.scan(ch)
    assert [mlc.get(f"M{30032 + k}") for k in range(3)] == [1, 1, 0] and mlc.get("M30000") == 1


@needs_veth
def test_m30000_and_eio_on_in_op_and_m30000_drops_when_a_slave_leaves(hil, program, tmp_path):
    trace = tmp_path / "ec.csv"
    with SimProcess("--io", "1", "--fault=leave:1@500", tag="s") as sim:
        r = hil("run", program(PROGRAM), "--bus", f"ethercat:{sim.iface}", "--mlc", "lathe",
                "--trace-signals", "M30000,M30032,M31256,M31257", "--trace", trace)
    assert r.code == 1 and "0x0601" in r.out + r.err, r.out + r.err
    m30000 = scanned(column(trace, "M30000"))
    eio = column(trace, "M30032")[-len(m30000):]
    z_connected = column(trace, "M31257")[-len(m30000):]
    drop = m30000.index(0)  # M30000 falls before the run ends …
    assert drop > 100 and set(m30000[:drop]) == {1} and set(m30000[drop:]) == {0}
    assert set(eio[:drop]) == {1}  # … the R1-EC (EIO node 501) was connected while in OP …
    assert set(z_connected[:drop]) == {1} and z_connected[-1] == 0  # … and Z's "connected" relay drops too
    assert set(column(trace, "M31256")[-len(m30000):]) == {1}  # X stayed on the line
