"""Servo parameters from a program: G10 L40/L41/L45/L46 with #20023/#20024 (NC5 App. B.3.4.1).

The program's request goes out on the bench's real link when the program reaches the block (the
motion before it finished), and the value read comes back into #20023 before the program reads on.
"""

from __future__ import annotations

import struct

import pytest

from fieldbus.link import SimLink
from hil.runner import BenchRunner
from hil.bench import default_lathe
from hil.session import make_link, sim_slaves
from nc.program import parse_program

WRITE_READ_BRANCH = """\
G00 X10. Z5.
G10 L41 I1 P2 D0 R150
G10 L40 I2 P1 D44
#100 = #20023
#101 = #20024
IF [#100 EQ 16777216] GOTO 80
G00 X30.
N80 G00 X20.
M30
"""


def _run(text: str, bus: str | None = None, **params: float):
    bench = default_lathe()
    if bus:
        bench.bus = bus
    bench.params.update(params)
    link = make_link(bench) if bus else SimLink(sim_slaves(bench), bench.cycle)
    runner = BenchRunner(bench, link)
    result = runner.run_program(parse_program(text, "prog.nc"))
    return runner, link, result


def _sdo(link, position: int, index: int) -> int:
    return struct.unpack("<i", link.sdo_read(position, index, 0)[:4])[0]


def test_offline_path_lists_writes_and_leaves_reads_vacant(hil, program):
    p = program(WRITE_READ_BRANCH)
    r = hil("path", p, "--vars", "100-101")
    assert r.code == 0, r.err
    lines = r.out.splitlines()
    assert lines[0].startswith("# work coordinates")
    assert lines[2] == "    2 servo  write P2-00 = 150 on station 1 -- not sent (offline, #20024 = -2)"
    assert lines[3] == "    3 servo  read P1-44 on station 2 -- not sent (offline, #20024 = -2)"
    assert lines[-1] == "vars #100=vacant #101=-2.0"
    # the branch is not taken offline (#100 is vacant): X30 runs before X20
    assert [l.split()[-1] for l in lines if " rapid " in l] == ["Z5", "Z5", "Z5"]
    assert "X30" in lines[4] and "X20" in lines[5]
    j = hil("path", p, "--json").json_lines()
    servo = [e for e in j if e["kind"] == "servo"]
    assert servo[0] == {"kind": "servo", "line": 2, "block": "G10 L41 I1 P2 D0 R150", "station": 1,
                        "object": "P2-00", "write": 150, "value": None, "result": -2}


@pytest.mark.parametrize("block, why", [
    ("G10 L40 I1 P2", "needs D"),
    ("G10 L41 I1 P2 D0", "needs R"),
    ("G10 L40 I1 P12 D0", "P12 (parameter group)"),
    ("G10 L40 I0 P2 D0", "I0 (station address)"),
    ("G10 L40 I1 P2 D0 R5", "R is only for L41"),
    ("G10 L41 I1 P2 D0 R1.5", "R1.5 (value)"),
    ("G10 L45 I1 P70000 D0", "object index"),
])
def test_syntax_errors_are_alarm_0x0252_with_line_and_block(hil, program, block, why):
    r = hil("path", program(f"G00 X10.\n{block}\nM30\n"))
    assert r.code == 1
    assert f"ALARM 0x0252 in prog.nc at line 2: {block} --" in r.err and why in r.err


def test_program_writes_a_parameter_after_the_motion_before_it_and_reads_and_branches():
    bench = default_lathe()
    drives = sim_slaves(bench)
    seen = []
    # the drive reacts to the write: record where X stood and whether it still moved
    drives[0].servo_params.on_write = lambda g, n, v: seen.append((g, n, v, drives[0].command, drives[0].position))
    link = SimLink(drives, bench.cycle)
    runner = BenchRunner(bench, link)
    result = runner.run_program(parse_program(WRITE_READ_BRANCH, "prog.nc"))
    assert result.ok, result.alarms
    x_counts = bench.axes[0].scaling.to_counts(5.0)  # X10. is a diameter: 5 mm of travel
    assert len(seen) == 1
    g, n, v, command, pos = seen[0]
    assert (g, n, v) == (2, 0, 150)
    # the G00 had finished: its command stood at the end point, the drive within 5 µm of it
    assert command == pytest.approx(x_counts, abs=1) and abs(pos - x_counts) < 0.005 * 256000
    assert _sdo(link, 0, 0x2200) == 150  # the drive's object dictionary holds it
    assert drives[0].servo_params.read("P2-00") == 150 and drives[1].servo_params.read("P2-00") == 35
    assert runner._interp.variable(100) == 16777216.0 and runner._interp.variable(101) == 0.0
    assert result.final["X"] == pytest.approx(10.0, abs=1e-3)  # branched to N80 X20. (radius 10)


def test_branch_follows_the_value_the_drive_holds():
    bench = default_lathe()
    drives = sim_slaves(bench)
    drives[1].servo_params.write("P1-44", 1000)
    runner = BenchRunner(bench, SimLink(drives, bench.cycle))
    result = runner.run_program(parse_program(WRITE_READ_BRANCH, "prog.nc"))
    assert result.ok, result.alarms
    assert runner._interp.variable(100) == 1000.0
    assert result.final["X"] == pytest.approx(10.0, abs=1e-3)  # X30. then X20.: the G00 X30 ran first


def test_a_parameter_that_does_not_exist_is_alarm_0x0252_with_line_and_block(hil, program):
    p = program("G00 X10. Z5.\nG10 L40 I1 P2 D99\nG00 X40.\nM30\n")
    r = hil("run", p)
    assert r.code == 1
    assert "ALARM 0x0252 in prog.nc at line 2: G10 L40 I1 P2 D99 --" in r.out
    assert "SDO abort 0x06020000 (object does not exist)" in r.out and "#20024 = 100794368" in r.out
    assert "final machine position  X 5.0000  Z 5.0000" in r.out  # stopped before the G00 X40.


def test_a_refused_write_changes_nothing_and_stops():
    runner, link, result = _run("G10 L41 I1 P2 D0 R99999\nG00 X40.\nM30\n")
    assert [a.code for a in result.alarms] == [0x0252] and result.alarms[0].line == 1
    assert "SDO abort 0x06090030 (value out of range)" in result.alarms[0].message
    start = default_lathe().axes[0].start
    assert _sdo(link, 0, 0x2200) == 35 and result.final["X"] == pytest.approx(start, abs=1e-6)  # G00 X40. never ran


def test_with_alarms_off_the_program_reads_the_result_code_and_goes_on():
    text = "G10 L40 I1 P2 D99\n#100 = #20024\n#101 = #20023\nIF [#100 NE 0] GOTO 9\nG00 X40.\nN9 G00 X8.\nM30\n"
    runner, _link, result = _run(text, **{"servo param alarm": 0})
    assert result.ok, result.alarms
    assert runner._interp.variable(100) == float(0x06020000) and runner._interp.variable(101) is None
    assert result.final["X"] == pytest.approx(4.0, abs=1e-3)


def test_station_that_is_not_on_the_bench_answers_nothing():
    _runner, _link, result = _run("G10 L40 I9 P2 D0\nM30\n")
    assert result.alarms[0].code == 0x0252 and "no drive at station 9" in result.alarms[0].message
    assert "#20024 = -1" in result.alarms[0].message


def test_l45_l46_address_objects_by_index_and_sub_index():
    # 0x2200 = 8704 is P2-00; L46 writes it as an object, L45 reads it back
    runner, link, result = _run("G10 L46 I2 P8704 D0 R77\nG10 L45 I2 P8704 D0\n#100 = #20023\nM30\n")
    assert result.ok, result.alarms
    assert runner._interp.variable(100) == 77.0 and _sdo(link, 1, 0x2200) == 77


def test_over_canopen_virtual(program, hil):
    runner, link, result = _run(WRITE_READ_BRANCH, bus="canopen:virtual")
    assert result.ok, result.alarms
    assert runner._interp.variable(100) == 16777216.0
    assert result.final["X"] == pytest.approx(10.0, abs=1e-3)
    # a write refused by the CANopen node: its SDO abort code reaches the alarm
    r = hil("run", program("G10 L41 I1 P0 D0 R5\nM30\n"), "--bus", "canopen:virtual")
    assert r.code == 1 and "SDO abort 0x06010002 (read-only)" in r.out and "at line 1" in r.out
    # and `hil servo` reaches the same object over CANopen
    r = hil("servo", "set", "Z", "P2-00", "88", "--bus", "canopen:virtual")
    assert r.code == 0 and "P2-00 set 88 → 88" in r.out and "over SDO (canopen:virtual)" in r.out, r.err


def test_over_modbus_rtu_on_a_pty(hil, program):
    from virtual_bus.drive import Cia402Drive
    from virtual_bus.modbus_drive import PtyModbusDrive

    drive = Cia402Drive(name="X")
    srv = PtyModbusDrive(drive.servo_params).start()
    try:
        # the drive answers at its factory station 0x7F = 127
        text = "G10 L41 I127 P2 D4 R640\nG10 L40 I127 P2 D4\n#100 = #20023\nIF [#100 NE 640] GOTO 9\nM30\n" \
               "N9 #20020 = 1\n"
        r = hil("run", program(text), "--servo-modbus", srv.device)
        assert r.code == 0, r.out + r.err
        assert drive.servo_params.read("P2-04") == 640
        r = hil("run", program("G10 L40 I127 P6 D50\nM30\n"), "--servo-modbus", srv.device)
        assert r.code == 1 and "ALARM 0x0252" in r.out and "exception 0x02" in r.out
    finally:
        srv.stop()


def test_over_ethercat_in_a_network_namespace(tmp_path):
    """pysoem against the emulated ASDA-A3-E slaves (`hil sim ethercat` on a veth pair); needs root."""
    import subprocess
    import sys
    from pathlib import Path

    from virtual_bus.ethercat.veth import SimProcess, can_create

    reason = can_create()
    if reason is not None:
        pytest.skip(reason)
    root = Path(__file__).resolve().parents[1]
    prog = tmp_path / "prog.nc"
    prog.write_text(WRITE_READ_BRANCH.replace("G10 L41 I1 P2 D0 R150", "G10 L41 I1 P2 D0 R150\nG10 L40 I1 P2 D99"))

    def hil(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "hil.cli", *args], capture_output=True, text=True, cwd=root,
                              timeout=120)

    with SimProcess(tag="sp") as sim:
        bus = f"ethercat:{sim.iface}"
        r = hil("run", str(prog), "--bus", bus)
        assert r.returncode == 1, r.stdout + r.stderr
        assert "ALARM 0x0252 in prog.nc at line 3: G10 L40 I1 P2 D99" in r.stdout
        assert "SDO abort 0x06020000" in r.stdout
        r = hil("servo", "get", "X", "P2-00", "--bus", bus)  # the write before it reached the drive
        assert r.returncode == 0 and "P2-00 = 150" in r.stdout, r.stdout + r.stderr
        prog.write_text(WRITE_READ_BRANCH)
        r = hil("run", str(prog), "--bus", bus)
        assert r.returncode == 0, r.stdout + r.stderr
        assert "final machine position  X 10.0000  Z 5.0000" in r.stdout  # read P1-44 and branched


def test_the_shipped_example_runs_on_the_default_bench_and_stops_offline(hil):
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "examples" / "servo_params.nc"
    r = hil("run", example)
    assert r.code == 0, r.out + r.err
    assert "final machine position  X 10.0000  Z 5.0000" in r.out and "result         completed" in r.out
    r = hil("path", example)  # no drive offline: #20024 = -2, the example stops with its macro alarm
    assert r.code == 1 and "ALARM MR1" in r.err and "line 17" in r.err
