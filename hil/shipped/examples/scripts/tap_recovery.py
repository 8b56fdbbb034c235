"""An interrupted rigid tap and its recovery (NC5 G command guide §3.13.2 G74/G84 note (6)) on the 3-axis mill:

    hil script examples/scripts/tap_recovery.py --bench benches/mill-3axis.toml

A G84 (S600 F900: pitch 1.5 mm) to Z-15 is cut off by the E-stop with the tap 5 mm in the hole: alarms 0x0401,
0x0270, 0x0C09 and the tapping interrupt status, which a reset does not end. A G01 in MDI is refused (0x0270);
G84.48 retracts Z to the R point with the spindle turning back, locked to the pitch, and the status ends. (M2x707
from the MLC does the same retraction; M2x080 cancels the status without moving.)
"""

PROGRAM = """G17 G90 G94 G00 X0. Y0. Z10.
M03 S600
G99 G84 X0. Y0. Z-15. R2. F900.
G80 G00 Z10.
M05
M30
"""


def main(machine):
    ch = machine.start_program(PROGRAM, "tap")
    machine.wait_until(lambda: machine.command("Z") < -5.0, 20.0, "the tap 5 mm in the hole")
    machine.estop()
    machine.wait(0.5)
    machine.estop(False)
    machine.reset()
    machine.wait(0.5)
    rec = ch.tap.record
    print("interrupted:", ", ".join(f"{a.code_text} (line {a.line})" for a in ch.alarms))
    print(f"record: {rec.axis} setpoint {rec.reached:.4f} when interrupted, R {rec.r_level:.4f}, pitch {rec.pitch:.4f} mm, "
          f"{'G95' if rec.per_rev else 'G94'} F{rec.feed:g} S{rec.rpm:g}, line {rec.line}")
    machine.mdi("G01 Z20. F500.")
    print("G01 while the status holds:", ", ".join(a.code_text for a in machine.runner.channel.alarms),
          f"Z {machine.position('Z'):.4f}")
    machine.reset()
    turns0 = machine.runner.spindle_actual_angle()
    took = machine.mdi("G84.48")
    turns = (machine.runner.spindle_actual_angle() - turns0) / 360.0
    print(f"G84.48: Z {machine.command('Z'):.4f} after {took:.3f} s, the spindle {turns:+.3f} turns, "
          f"status {'holds' if machine.runner.channel.tap.holds else 'ended'}")
    machine.mdi("G00 Z10.\nM05")
