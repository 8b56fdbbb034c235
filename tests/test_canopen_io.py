"""Remote I/O over CANopen (python-can `virtual`, lock-step): the bench's [[io]] stations are
simulated CiA 401 nodes (fieldbus/canopen/eds/delta_dio_401.eds); the master configures their
TPDO1 (inputs, 0x6000:n) and RPDO1 (outputs, 0x6200:n) and maps them to MLC X/Y devices.

Latency: an input switched before the cycle's SYNC is read by the user scan of that cycle
(0 cycles) — on SYNC ("sync" stations) or in the change-of-state TPDO that left when it switched
("change"). An output written by the user scan of cycle N travels in the RPDO of cycle N+1 and acts
on that SYNC (1 cycle). A station that goes silent: inputs 0 and its EIO relay off once its
heartbeat is overdue, with alarm 0x1426; NMT stop at the end puts its outputs in their safe state."""

from __future__ import annotations

import subprocess
from types import SimpleNamespace

import pytest

from fieldbus.link import BusError
from hil.bench_file import parse_bench
from hil.scripting import Machine
from hil.session import make_link
from mlc.machine import Mlc
from tests.test_canopen_process import netns  # noqa: F401  (fixture: a namespace for udp_multicast)

BENCH = """
bus = "canopen:virtual"
[[axes]]
name = "X"
start = 10.0
[[spindles]]
name = "S1"
[[io]]
canopen_node = 40
[[io]]
name = "valves"
inputs = 8
outputs = 8
canopen_node = 41
canopen_tpdo = "change"
"""


def start(scans: list) -> Machine:
    bench = parse_bench(BENCH)

    def scan(mlc):
        scans.append((mlc.scan_count, mlc.x(3), mlc.x(16), mlc.m("M30032"), mlc.m("M30033")))
        for k in range(16):
            mlc.y(k, mlc.x(k))
        mlc.y(16 + 7, mlc.x(16))
    mlc = Mlc(SimpleNamespace(scan=scan), axes=bench.axis_names, cycle=bench.cycle, motion=bench.motion_config())
    m = Machine(bench, mlc, make_link(bench))
    m.power_up()
    return m


def test_master_configures_the_cia401_stations_over_sdo():
    m = start([])
    try:
        first, valves = m.link.io_devices
        assert [(i.name, i.kind, i.layout) for i in m.link.infos[2:]] == [("EIO-501", "io", "cia401"),
                                                                          ("valves", "io", "cia401")]
        assert first.nmt_state == valves.nmt_state == "OPERATIONAL"
        v = first._value
        assert v(0x1017, 0) == 20 and v(0x1800, 1) & 0x7FF == 0x180 + 40 and v(0x1800, 2) == 1
        assert [v(0x1A00, s) for s in range(1, v(0x1A00, 0) + 1)] == [0x60000108, 0x60000208]  # 16 inputs
        assert [v(0x1600, s) for s in range(1, v(0x1600, 0) + 1)] == [0x62000108, 0x62000208]
        assert valves._value(0x1800, 2) == 255 and valves._value(0x1A00, 0) == 1  # change of state, 8 inputs
    finally:
        m.close()
    assert first.nmt_state == "STOPPED"


@pytest.mark.parametrize("station,point,device", [(0, 3, 1), (1, 0, 2)], ids=["on-sync", "on-change"])
def test_input_reaches_x_in_the_same_cycle_and_y_acts_on_the_next_sync(station, point, device):
    scans: list = []
    m = start(scans)
    io = m.link.io_devices[station]
    m.cycle(5)
    sent = io.syncs
    io.set_input(point, True)
    n = len(scans)
    m.cycle(1)
    assert scans[n][device] is True  # seen by the user scan of the very next cycle
    out_point = 3 if station == 0 else 7
    assert not io.output(out_point)  # the scan's output is still on its way
    m.cycle(1)
    assert io.output(out_point) and io.history[-1] == (sent + 2, 1 << out_point)  # acted on the next SYNC
    m.close()
    assert io.outputs == 0  # NMT stop: error mode 0x6206 all set, error value 0 → outputs off


def test_change_of_state_station_sends_only_when_an_input_changes():
    m = start([])
    valves = m.link.io_devices[1]
    frames = []
    m.link.network.subscribe(0x180 + 41, lambda cob, data, ts: frames.append(bytes(data)))
    m.cycle(20)
    assert frames == []  # no change, no TPDO (the first one went out right after NMT start)
    valves.set_input(5, True)
    valves.set_input(6, True)
    m.cycle(20)
    assert frames == [b"\x20", b"\x60"] and m.get("X21") == 1 and m.get("X22") == 1
    m.close()


def test_a_silent_station_reads_zero_drops_its_relay_and_raises_0x1426():
    scans: list = []
    m = start(scans)
    valves = m.link.io_devices[1]
    valves.set_input(0, True)
    m.cycle(10)
    assert scans[-1][2:] == (True, True, True)
    valves.power_off()
    t_off = m.time
    with pytest.raises(BusError) as err:
        m.cycle(200)
    assert err.value.alarm.code == 0x1426 and "valves" in err.value.alarm.message
    assert m.time - t_off == pytest.approx(m.link.heartbeat_timeout, abs=0.021)  # one heartbeat period late at most
    m.cycle(2)  # the run can go on scanning: the lost station is no longer served or supervised
    assert scans[-1][2:] == (False, True, False)  # X16 safe 0, EIO 501 still on, EIO 502 off
    assert m.get("X16") == 0 and m.get("M30033") == 0
    m.close()


def test_hil_run_over_canopen_virtual_switches_coolant_on_the_cia401_station(hil, program, tmp_path):
    import csv

    from tests.conftest import ROOT

    trace = tmp_path / "t.csv"
    r = hil("run", program("M08\nG04 X0.05\nM09\nM30\n"), "--bench", ROOT / "benches" / "lathe-io.toml",
            "--bus", "canopen:virtual", "--trace", trace, "--trace-signals", "Y0,M30032,M30033")
    assert r.code == 0, r.out + r.err
    rows = list(csv.DictReader(trace.open()))
    y0 = [int(float(r["Y0"])) for r in rows]
    assert 1 in y0 and y0[-1] == 0
    assert int(float(rows[-1]["M30032"])) == 1 and int(float(rows[-1]["M30033"])) == 1


def test_hil_run_switches_an_io_station_served_by_hil_sim_canopen_in_another_process(netns, tmp_path):
    """Real time across processes (udp_multicast in a namespace): `hil sim canopen --bench` serves the
    drives and the CiA 401 stations; M08/M09 switch Y0 on station 64 and back."""
    import csv

    from tests.conftest import ROOT
    from tests.test_canopen_process import _in_ns, _Sim

    group = "239.74.163.4"
    bench = tmp_path / "lathe-io-4ms.toml"
    bench.write_text((ROOT / "benches" / "lathe-io.toml").read_text().replace("cycle_ms = 1.0", "cycle_ms = 4.0"))
    prog = tmp_path / "coolant.nc"
    prog.write_text("M08\nG04 X0.1\nM09\nM30\n")
    trace = tmp_path / "t.csv"
    sim = _Sim(netns, group, "--bench", str(bench))
    try:
        assert "64=EIO-501, 65=valves" in sim.banner, sim.banner
        run = subprocess.run(_in_ns(netns, "-m", "hil.cli", "run", str(prog), "--bench", str(bench),
                                    "--bus", f"canopen:udp_multicast:{group}", "--trace", str(trace),
                                    "--trace-signals", "Y0,M30032,M30033"),
                             capture_output=True, text=True, timeout=60, cwd=ROOT)
    finally:
        err = sim.stop()
    assert run.returncode == 0, run.stdout + run.stderr
    rows = list(csv.DictReader(trace.open()))
    assert 1 in [int(float(r["Y0"])) for r in rows] and int(float(rows[-1]["Y0"])) == 0
    assert int(float(rows[-1]["M30032"])) == 1 and int(float(rows[-1]["M30033"])) == 1
    assert "64 STOPPED, " in err and "outputs changed 2 times" in err, err  # Y0 on at M08, off at M09
