"""The MLC's servo relays obeyed by the bench (decision M22-1), as `hil run --at` sets them on the lathe bench (X is
the channel's 1st axis, Z its 2nd): M2x012 "Servo ON/OFF" for every axis, M2x272+i "Servo OFF" for one. Read from
the trace: positions, the drives' CiA 402 statuswords, the servo status relays M3x272+i and the alarms."""

from __future__ import annotations

import csv
import io

import pytest

PROGRAM = "G98 G01 X40. F3000\nZ90.\nM30\n"
SIGNALS = "M31272,M31273"


def _enabled(sw: str) -> bool:
    return int(sw) & 0x6F == 0x27  # CiA 402 operation enabled


def _run(hil, tmp_path, *at: str, bus: str = "sim"):
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    trace = tmp_path / f"p-{len(at)}.csv"
    args = [a for e in at for a in ("--at", e)]
    r = hil("run", str(prog), "--no-check", "--bus", bus, "--trace", str(trace), "--trace-signals", SIGNALS, *args)
    return r, list(csv.DictReader(trace.open()))


def test_servo_off_while_moving_stops_under_control_with_0A07_and_disables_at_standstill(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "t=0.3:set M21012=0")
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x0A07 axis X at line 1" in r.out and "M21012 OFF" in r.out and "result         STOPPED" in r.out
    k = next(i for i, row in enumerate(rows) if "0x0A07" in row["alarm"])
    assert abs(float(rows[k]["X_vel"])) > 40.0  # X ran at F3000 (50 mm/s) when the relay went OFF
    # a controlled stop: the speed falls over tens of cycles, no jump; the drive stays enabled until X stands
    speeds = [abs(float(row["X_vel"])) for row in rows[k:]]
    assert all(b <= a + 1.0 for a, b in zip(speeds, speeds[1:]))
    assert sum(1 for v in speeds if v > 1.0) > 30
    off = next(i for i, row in enumerate(rows) if i > k and not _enabled(row["X_sw"]))
    assert abs(float(rows[off - 1]["X_vel"])) < 0.01 and rows[off]["M31272"] == "0"
    # X40 is a diameter: the block ends at 20 mm; X stood short of it, past where the relay fell
    assert 20.5 < float(rows[-1]["X_act"]) < float(rows[k]["X_act"]) - 1.0
    # Z, standing, is disabled at once after the stop's planner idles, while X still brakes
    assert any(not _enabled(row["Z_sw"]) and _enabled(row["X_sw"]) for row in rows[k:])


@pytest.mark.parametrize("bus", ["sim", "canopen:virtual"])
def test_axis_servo_off_disables_that_axis_only_and_a_move_of_it_raises_0A07(hil, tmp_path, bus):
    r, rows = _run(hil, tmp_path, "cycle=1:set M21273=1", bus=bus)
    assert r.code == 1, r.out + r.err
    assert "ALARM 0x0A07 axis Z at line 2" in r.out and "M21273 ON" in r.out
    line1 = [row for row in rows if row["line"] == "1"]
    # X runs its block to X40 (diameter: 20 mm) while Z stands disabled (M3x273 OFF, not operation enabled)
    assert float(line1[-1]["X_act"]) == pytest.approx(20.0, abs=0.2)
    assert all(_enabled(row["X_sw"]) and row["M31272"] == "1" for row in line1[10:])
    assert all(not _enabled(row["Z_sw"]) and row["M31273"] == "0" for row in line1[10:])
    # Z90 is refused: Z never leaves Z100, the run stops
    assert all(float(row["Z_act"]) == pytest.approx(100.0, abs=1e-6) for row in rows)
    assert "final machine position  X 20.0000  Z 100.0000" in r.out


def test_axis_servo_on_again_enables_it_where_it_stands_and_the_program_runs_unchanged(hil, tmp_path):
    r, rows = _run(hil, tmp_path, "cycle=1:set M21273=1", "t=0.2:set M21273=0")
    assert r.code == 0, r.out + r.err
    assert "alarms         none" in r.out and "Z 90.0000" in r.out
    back = next(i for i, row in enumerate(rows) if i > 10 and _enabled(row["Z_sw"]))
    assert 0.2 < float(rows[back]["t"]) < 0.21 and rows[back]["M31273"] == "1"
    assert any(not _enabled(row["Z_sw"]) for row in rows[10:back])
    _, plain = _run(hil, tmp_path)  # the same program with the relays untouched: the same commands, cycle by cycle
    assert [(row["X_cmd"], row["Z_cmd"]) for row in rows] == [(row["X_cmd"], row["Z_cmd"]) for row in plain]


USER_MLC = '''"""M08 turns the Z axis servo OFF (M2x273) for 0.3 s; every code finishes after 20 ms."""
SCAN_ON_CHANGE = True


def scan(mlc):
    strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")
    if mlc.m("M_STROBE") and int(mlc.d("M_CODE")) == 8:
        mlc.state["off"] = True
    if mlc.state.get("off"):
        mlc.set("M21273", True)
        if mlc.timer("on", 0.3, True):
            mlc.set("M21273", False)
            mlc.state["off"] = False
            mlc.timer("on", 0, False)
    if not strobe:
        mlc.set("MST_FINISH", False)
        return
    if mlc.timer("fin", 0.02, True):
        mlc.timer("fin", 0, False)
        mlc.set("MST_FINISH")
'''


@pytest.mark.parametrize("stretch", ["0", "1"])
def test_a_user_mlc_turns_an_axis_off_during_a_dwell_and_back_on_stepped_or_stretched(hil, tmp_path, monkeypatch,
                                                                                    stretch):
    """A gated user MLC (SCAN_ON_CHANGE) drives M2x273 on a timer: Z is off through the dwell, on again for Z90;
    the trace is the same whether quiet cycles are stepped (DELTAHIL_STRETCH=0) or stretched."""
    (tmp_path / "servo_mlc.py").write_text(USER_MLC)
    prog = tmp_path / "q.nc"
    prog.write_text("G98 G01 X40. F3000\nM08\nG04 X0.5\nZ90.\nG04 X1.\nM30\n")
    traces = {}
    for s in ("0", stretch):
        monkeypatch.setenv("DELTAHIL_STRETCH", s)
        trace = tmp_path / f"q{s}.csv"
        r = hil("run", str(prog), "--no-check", "--mlc", str(tmp_path / "servo_mlc.py"), "--trace", str(trace),
                "--trace-signals", "M31273,M21273")
        assert r.code == 0 and "alarms         none" in r.out and "Z 90.0000" in r.out, r.out + r.err
        traces[s] = trace.read_text()
    assert traces["0"] == traces[stretch]
    rows = list(csv.DictReader(io.StringIO(traces["0"])))
    dwell = [row for row in rows if row["line"] == "3"]
    assert not _enabled(dwell[10]["Z_sw"]) and dwell[10]["M31273"] == "0"  # off in the dwell
    z_moving = [row for row in rows if row["line"] == "4" and float(row["Z_act"]) < 99.9]
    assert z_moving and all(_enabled(row["Z_sw"]) for row in z_moving)  # on again when Z90 runs
