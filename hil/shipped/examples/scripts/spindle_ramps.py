"""Spindle start / speed steps / reverse / stop through M03/M04/M05 S and the MLC handshake.

    hil script examples/scripts/spindle_ramps.py
"""


def main(machine):
    for rpm in (500, 1500, 3000):
        took = machine.spindle(rpm)
        machine.wait(0.2)
        print(f"M03 S{rpm}: speed reached after {took:.3f} s, drive at {machine.get_rpm():.1f} rpm")
    machine.spindle_override(50)  # D21026
    machine.wait(0.3)
    print(f"override 50 %: drive at {machine.get_rpm():.1f} rpm")
    machine.spindle_override(100)
    took = machine.spindle(1000, direction=-1)
    print(f"M04 S1000: reversed in {took:.3f} s, drive at {machine.get_rpm():.1f} rpm")
    print(f"M05: stopped in {machine.spindle(0):.3f} s")
