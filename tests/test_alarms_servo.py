"""NC5 App. A.2.2 axis alarms from the virtual drives: a drive fault injected at power-up or mid-program,
or a bench whose drive has a limit switch, and the alarm the NC raises, with the axes stopped under
control afterwards (tests/fault_helpers.py). docs/alarms.md lists these tests as the ones raising the codes.
"""

from __future__ import annotations

import json

from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.cli import main
from hil.runner import OVERSPEED, BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program
from tests.conftest import ROOT
from tests.fault_helpers import Recorder, assert_stopped_after_alarm
from virtual_bus.drive import AL_EMERGENCY

PROGRAM = "G98\nG00 X80. Z-20.\nG01 X100. Z-60. F3000\nM30\n"


def _runner(inject=None):
    bench = default_lathe()
    drives = sim_slaves(bench)
    rec = Recorder(chain=inject)
    return BenchRunner(bench, SimLink(drives, bench.cycle), on_cycle=rec), drives, rec


def test_0x0a07_servo_not_ready_when_an_axis_drive_will_not_enable():
    """App. A 0x0A07 'Servo is not ready. The axis is not servo ON.': the Z drive's emergency-stop input
    (ASDA AL013) is active at power-up, so Z never reaches Operation enabled; nothing moves."""
    runner, drives, _ = _runner()
    drives[1].external_fault = AL_EMERGENCY
    result = runner.run_program(parse_program(PROGRAM))
    codes = [(a.code, a.axis) for a in result.alarms]
    assert (0x0A07, "Z") in codes  # the alarm code, on the Z drive
    assert 0x0C06 not in [c for c, _ in codes]  # an axis, not the spindle
    assert not result.finished and all(abs(d.velocity) < 1 for d in drives)
    assert result.final["X"] == default_lathe().axes[0].start  # no motion was commanded


def test_0x0c06_spindle_not_enabled_when_the_spindle_drive_will_not_enable():
    """App. A 0x0C06 'The spindle is not enabled. Please check if the spindle is enabled.': the spindle
    drive (S1) is in fault at power-up; the axes' drives enabled, so it is not 0x0A07."""
    runner, drives, _ = _runner()
    drives[2].external_fault = AL_EMERGENCY
    result = runner.run_program(parse_program(PROGRAM))
    codes = [(a.code, a.axis) for a in result.alarms]
    assert (0x0C06, "S1") in codes  # the alarm code on the spindle drive
    assert 0x0A07 not in [c for c, _ in codes]  # the axes are servo ON
    assert not result.finished


def test_0x0602_overspeed_protection_on_a_runaway_axis():
    """App. A 0x0602 'Overspeed protection. System overspeed protection.': in the middle of a feed move the
    X drive's position loop turns into positive feedback (its gain's sign flips, as a reversed encoder
    does), so X runs away from its setpoint towards the motor's top speed, which is above the axis limit.
    The NC raises 0x0602 on X once X is measured beyond OVERSPEED x its limit, before the drive's own
    following-error alarm, and stops the axes under control."""
    bench = default_lathe()
    assert bench.axes[0].drive.max_speed_rpm / 60 * bench.axes[0].scaling.lead > OVERSPEED * bench.axes[0].limits.max_velocity

    def reverse(r: BenchRunner) -> None:
        if r.cycle == 300:
            drives[0].params.kp = -abs(drives[0].params.kp)

    runner, drives, rec = _runner(reverse)
    result = runner.run_program(parse_program(PROGRAM))
    a = result.alarms[0]
    assert (a.code, a.axis) == (0x0602, "X"), result.alarms
    assert "overspeed" in a.message
    assert not result.finished
    assert_stopped_after_alarm(rec, result, lost=("X",))  # Z brakes within its limits; X's drive ramps itself


def test_0x0602_is_not_raised_by_a_normal_run_at_the_axis_limit():
    """The protection does not bite on a rapid at the axes' full speed (the overshoot of the position loop
    stays far below the margin)."""
    runner, _, _ = _runner()
    result = runner.run_program(parse_program("G00 X150. Z-300.\nG00 X20. Z100.\nM30\n"))
    assert result.ok, result.alarms


def test_0x0402_hardware_limit_from_the_drive_limit_switch(tmp_path, capsys):
    """App. A 0x0402 'Hardware limit signal is triggered.': `hil run` on a bench whose X drive has its
    positive limit switch at 85 mm (inside the soft limits), a program that feeds X to 90 mm: the drive sets
    its internal-limit bit (CiA 402 statusword bit 11), the NC raises 0x0402 on X at the moving line, exit 1."""
    text = (ROOT / "benches" / "lathe-2axis.toml").read_text()
    old = 'drive = { model = "asda-a3", kp = 120.0, kff = 0.95 }'
    assert old in text
    counts = 85 * 1_280_000 // 5  # 85 mm on a 5 mm lead at 1,280,000 counts/rev
    (tmp_path / "b.toml").write_text(text.replace(old, old[:-2] + f", positive_limit = {counts} }}"))
    (tmp_path / "p.nc").write_text("G98\nG01 U60. F3000\nM30\n")  # X from 60 to 90 (radius)
    capsys.readouterr()
    code = main(["run", str(tmp_path / "p.nc"), "--bench", str(tmp_path / "b.toml"), "--json", "--no-progress"])
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 1
    assert [(a["code"], a["axis"], a["line"]) for a in summary["alarms"]] == [("0x0402", "X", 2)]
    assert 84.9 < summary["final_position"]["X"] <= 85.0 + 1e-3  # held at the switch


def _hil_run(capsys, argv: list[str]) -> tuple[int, dict]:
    capsys.readouterr()
    code = main(["run", *argv, "--json", "--no-progress"])
    return code, json.loads(capsys.readouterr().out.strip().splitlines()[-1])


def test_0x0c01_spindle_positioning_failed_when_the_index_never_comes(tmp_path, capsys):
    """App. A 0x0C01 'Spindle positioning failed. ... check the spindle positioning time setting (N0.1025
    positioning check time for 1st spindle)': the C-axis lathe bench with a spindle encoder that gives no
    index pulse; M19 (N§3.8 / B.2.1.1 M2x706) stops the spindle and searches the index, never finds it, and
    after N0.1025 = 500 ms the NC raises 0x0C01 on S1 (exit 1)."""
    text = (ROOT / "benches" / "lathe-c-axis.toml").read_text()
    old = '[[spindles]]\nname = "S1"\nmax_rpm = 4000.0'
    assert old in text
    text = text.replace(old, old + "\ndrive = { index_pulse_every = 1000000000000 }")  # no index in reach
    text = text.replace("[[axes]]", '[params]\n"N0.1025" = 500\n\n[[axes]]', 1)
    (tmp_path / "b.toml").write_text(text)
    (tmp_path / "p.nc").write_text("O3\nM19\nG04 X0.1\nM20\nM30\n")
    code, out = _hil_run(capsys, [str(tmp_path / "p.nc"), "--bench", str(tmp_path / "b.toml")])
    assert code == 1
    assert [(a["code"], a["axis"]) for a in out["alarms"]] == [("0x0C01", "S1")]
    assert "500 ms" in out["alarms"][0]["message"] and "seek-index" in out["alarms"][0]["message"]
    assert out["sim_time_s"] < 2.0  # raised at the check time, not at max_time


def test_0x0c0a_mlc_activates_the_spindle_alarm(tmp_path, capsys):
    """App. A 0x0C0A 'MLC activate spindle alarm' / B.2.1.1 M2x711 '1st Spindle Alarm: when the MLC receives
    an alarm signal from digital input and then triggers this special M, the system will stop NC process':
    a user MLC wired to the spindle drive's alarm relay sets M2x711 0.3 s into the program; the run ends
    with 0x0C0A (exit 1) and the axes stop under control."""
    mlc = tmp_path / "relay.py"
    mlc.write_text('def scan(mlc):\n'
                   '    strobe = mlc.m("M_STROBE") or mlc.m("S_STROBE") or mlc.m("T_STROBE")\n'
                   '    mlc.set("MST_FINISH", bool(strobe))\n'
                   '    if mlc.timer("relay", 0.3, True):  # the spindle drive alarm relay closes\n'
                   '        mlc.set("SPINDLE1_ALARM")\n')
    (tmp_path / "p.nc").write_text("G98\nG01 U-40. F1200\nG01 W-50.\nM30\n")
    code, out = _hil_run(capsys, [str(tmp_path / "p.nc"), "--mlc", str(mlc)])
    assert code == 1
    assert [a["code"] for a in out["alarms"]] == ["0x0C0A"]
    assert 0.3 <= out["program_time_s"] < 0.5  # the program stopped when the relay closed


def test_0x0c04_switching_to_c_on_a_bench_without_a_c_axis(tmp_path, capsys):
    """App. A 0x0C04 'Incorrect switching of the spindle and C-axis. Make sure ... whether the C-axis and the
    spindle are both configured as active axes': M66 (the lathe MLC's switch to C, NC5 §3.14.1) on the
    2-axis lathe bench, which has a spindle but no C axis; the run ends with 0x0C04 on S1 (exit 1)."""
    (tmp_path / "p.nc").write_text("O1\nM66\nG04 X0.2\nM77\nM30\n")
    code, out = _hil_run(capsys, [str(tmp_path / "p.nc"), "--bench", str(ROOT / "benches" / "lathe-2axis.toml")])
    assert code == 1
    assert [(a["code"], a["axis"]) for a in out["alarms"]] == [("0x0C04", "S1")]


TAP = "G90 G00 X0 Y0 Z10.\nM03 S600\nG84 X10. Y0 Z-15. R2. F900.\nG80\nG01 Z-30. F600\nM30\n"


def test_0x0270_0x0c09_estop_during_rigid_tapping(tmp_path, capsys):
    """App. A 0x0270 'Axis movement prohibition during tapping interruption' and 0x0C09 'Spindle movement
    prohibition during tapping interruption' (N§3.13 G84 note (6): 'If an unexpected interruption occurs in the
    tapping process, including reset, emergency stop ... the system will ... return the alarms [0x0270] and
    [0x0C09]'): E-stop while Z is in the hole (below Z-5 of a G84 to Z-15) on the mill bench; the E-stop's
    own 0x0401 first, then both, at the G84 line. An E-stop during an ordinary feed (Z below -20, line 5)
    raises 0x0401 alone."""
    (tmp_path / "p.nc").write_text(TAP)
    bench = str(ROOT / "benches" / "mill-3axis.toml")
    code, out = _hil_run(capsys, [str(tmp_path / "p.nc"), "--bench", bench, "--at", "Z<-5:estop"])
    assert code == 1
    assert [(a["code"], a["line"]) for a in out["alarms"]] == [("0x0401", None), ("0x0270", 3), ("0x0C09", 3)]
    code, out = _hil_run(capsys, [str(tmp_path / "p.nc"), "--bench", bench, "--at", "Z<-20:estop"])
    assert code == 1 and [a["code"] for a in out["alarms"]] == ["0x0401"]
